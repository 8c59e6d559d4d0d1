//! The registry of metaplate's drivers, as probe-rs lists its probes: one table of backends per capability
//! ([`backends::BACKENDS`]: name, what it needs, its cargo feature, whether this build has it, what is connected),
//! the hardware file that names one backend per instrument ([`HardwareFile`]), and opening the rig it names
//! ([`open_rig`]).
//!
//! - [`backends`]: [`Capability`] (`Vibrometer`, `Daq`, `Audio`, `Keypad`) and [`BACKENDS`]: `polytec` (a Polytec
//!   vibrometer controller over RS-232, serialport), `analog` (a vibrometer without a remote interface, its range
//!   declared), `labjack-u6` (a LabJack U6 over its documented USB functions, nusb), `nidaqmx` (an NI DAQ
//!   through NI-DAQmx, loaded at run time), `alsa` (the audio interface) and `hidraw` (the response keypad), each
//!   with what it needs, its feature, whether this build has it, and [`Backend::list`], the devices it can see.
//! - [`HardwareFile`]: the hardware file (format below), parsed and checked. Errors ([`HardwareError`]) name the
//!   file, the key and the reason, or the backend this build lacks and how to get it.
//! - [`open_rig`]: the [`Rig`](metaplate_core::rig::Rig) a hardware file names, on the real clock, and the keypad
//!   beside it ([`OpenedRig`]); [`open_plate_rig`] also reads the file's plate and checks the wiring against it.
//!   Every instrument is tried whatever became of the others: one error names each that failed
//!   ([`HardwareError::Devices`], [`HardwareError::failed_instruments`]), which `metaplate check` reports as a
//!   failed check per instrument.
//! - [`listing`]: what is connected, per backend ([`list_connected`], what `metaplate devices` prints), and a
//!   hardware file drafted from it ([`draft_hardware_file`]).
//!
//! # Drivers and features
//!
//! A driver is generic over a narrow transport trait (`SerialLine`, `BulkTransport`, `PcmSink`, `HidInput`) and
//! implements a capability trait from `metaplate-core` (`Vibrometer`, `Daq`, `AudioOut`); the mock device
//! implements the device side of the same protocol behind the same transport trait, so tests run the code the lab
//! runs. Real backends are cargo features of the driver crates (`metaplate-ldv/serial`: serialport;
//! `metaplate-daq/usb`: nusb; `metaplate-daq/nidaqmx`: libloading; `metaplate-audio/alsa` and
//! `metaplate-keypad/hidraw`: Linux only), and this crate's features turn them on (`serial`, `labjack-u6`,
//! `nidaqmx`, `alsa`, `hidraw`; all of them: `hardware`, the default here and in the binary). The workspace depends
//! on the drivers without them, so the mock devices, the mock lab, the recipes and a `cargo build -p metaplate-cli
//! --no-default-features` binary link none (`.ci/run` checks it with `cargo tree`). A build without a backend
//! still parses a file naming it and says, when asked to open it, that this build lacks it
//! ([`HardwareError::NotInThisBuild`]); elsewhere than Linux, `alsa` and `hidraw` are compiled out and the registry
//! says so.
//!
//! # The hardware file (TOML)
//! The one description of the format (`crates/cli/hardware.example.toml` is an example of it). Unknown keys are
//! refused (a typo must not fall back to a default); every instrument's section names its `backend`.
//! ```toml
//! # The plate under test: a scene (built-in name or scene file) whose outline, supports, measurement grid and
//! # actuator positions describe the real plate; its simulation settings are ignored.
//! plate = "metamaterial"
//!
//! [ldv]                      # the vibrometer
//! backend = "polytec"        # a Polytec controller on RS-232 (or "analog": range declared, nothing sent)
//! port = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A10K1234-if00-port0"
//! decoder = "VD-09"          # optional: the velocity decoder by name or index; else the first the unit has
//! baud = 115200              # optional; the controller speaks 115200 8N1 only, anything else is refused
//!
//! [daq]                      # the DAQ: either a LabJack U6 on USB ...
//! backend = "labjack-u6"
//! serial = "360012345"       # its serial number, as on its label (`metaplate devices` lists the U6s it sees)
//! resolution_index = 0       # optional (default 0): StreamConfig's ResolutionIndex, 0-8
//! settling_factor = 0        # optional (default 0: the U6 chooses): extra settling, 10 us steps
//! # ... or an NI DAQ through NI-DAQmx:
//! # backend = "nidaqmx"
//! # device = "Dev1"          # the NI device name (NI MAX)
//! # read_timeout_s = 10.0    # optional (default 10): longest wait for one block, s
//! # terminal, trigger, library, [daq.inputs.aiN]: optional, see `nidaqmx.rs` (NidaqmxDaq)
//!
//! [audio]                    # the multichannel audio interface
//! backend = "alsa"           # Linux only
//! device = "hw:CARD=24Ao,DEV=0"
//! sample_rate_hz = 48000.0
//! channels = 10
//!
//! [keypad]                   # optional: the response keypad
//! backend = "hidraw"         # Linux only
//! usb = "046d:c31c"          # VID:PID or VID:PID:SERIAL, ids in hex
//! report_id = 1              # optional: only for a composite device that prefixes its boot reports with an ID
//!
//! [wiring]                   # how it is cabled (checked by metaplate_core::rig::Wiring::validate)
//! actuator_channels = [0, 1, 2, 3, 4, 5, 6, 7]   # audio channel of each actuator, in the plate's actuator order
//! loopback_channel = 8       # audio channel cabled back into the DAQ
//! velocity_input = 0         # DAQ input of the LDV's velocity output
//! loopback_input = 1         # DAQ input of the loopback
//! daq_range_v = 10.0         # DAQ input range, +/- V
//! daq_sample_rate_hz = 24000.0
//! loopback_volts_per_full_scale = 1.0   # V at the DAQ for a full-scale audio sample
//! ```

pub mod aim;
pub mod backends;
mod file;
pub mod listing;
mod nidaqmx;
mod open;
mod zaber;

pub use backends::{BACKENDS, Backend, Capability, Found, ListError};
pub use file::{
    AlsaAudio, AlsaDaq, AnalogLdv, AudioSection, DaqSection, HardwareError, HardwareFile, HidrawKeypad, KeypadSection,
    LabjackU6Daq, LdvSection, PolytecLdv, UsbIds, WiringSection,
};
pub use listing::{Listing, draft_hardware_file, list_connected, listings_json, listings_text};
pub use nidaqmx::{NidaqmxDaq, NidaqmxInput};
pub use open::{OpenPurpose, OpenedRig, open_galvo_outputs, open_plate_rig, open_rig};
pub use zaber::{ZaberAim, ZaberAimAxis};
