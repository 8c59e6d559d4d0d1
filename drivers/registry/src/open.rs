//! Opening the rig a hardware file names, each instrument through its backend.

use std::path::Path;
use std::sync::Arc;

use metaplate_core::clock::{Clock, RealClock};
use metaplate_core::rig::Rig;
use metaplate_core::scene::Scene;
use metaplate_keypad::{HidInput, Keypad};

use crate::backends::{self, Capability};
use crate::file::{AudioSection, DaqSection, HardwareError, HardwareFile, KeypadSection, LdvSection};

/// What a hardware file opens: the rig the recipes drive, and the keypad beside it (not a capability of [`Rig`]:
/// no recipe reads it yet).
pub struct OpenedRig {
    /// The LDV, the DAQ and the audio interface on the real clock, with the file's wiring.
    pub rig: Rig,
    /// The response keypad, when the file has a `[keypad]`.
    pub keypad: Option<Keypad<Box<dyn HidInput>>>,
}

impl std::fmt::Debug for OpenedRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenedRig").field("keypad", &self.keypad.is_some()).finish_non_exhaustive()
    }
}

/// The plate the hardware file at `path` names (its scene, validated) and the rig and keypad it opens
/// ([`open_rig`]): the wiring must name one channel per actuator of the plate, which is checked before anything
/// is opened.
///
/// # Errors
/// [`HardwareError::File`] and the others of [`open_rig`]; [`HardwareError::Scene`] for the plate's scene;
/// [`HardwareError::Plate`] when the wiring does not fit it.
pub fn open_plate_rig(path: &Path) -> Result<(Scene, OpenedRig), HardwareError> {
    let file = HardwareFile::load(path)?;
    let scene = Scene::resolve(&file.plate)?;
    scene.validate()?;
    let actuators = file.wiring.actuator_channels.len();
    if actuators != scene.actuators.len() {
        let reason = format!(
            "wiring.actuator_channels lists {actuators} actuators, the plate `{}` has {}",
            file.plate,
            scene.actuators.len()
        );
        return Err(HardwareError::Plate { path: path.to_path_buf(), reason });
    }
    Ok((scene, open_rig(&file)?))
}

/// Opens every instrument `file` names, in the order LDV, DAQ, audio interface (configured once at the file's
/// rate and channel count, so that a missing card is found now rather than at the first point), keypad; on the
/// real clock.
///
/// # Errors
/// [`HardwareError::NotInThisBuild`] for the first backend this build lacks, before anything is opened;
/// [`HardwareError::Device`] naming the first instrument that cannot be opened.
pub fn open_rig(file: &HardwareFile) -> Result<OpenedRig, HardwareError> {
    for (capability, name) in file.backends() {
        if let Some(backend) = backends::find(capability, name)
            && let Some(reason) = backend.missing_reason()
        {
            return Err(HardwareError::NotInThisBuild {
                path: file.path.clone(),
                key: format!("{}.backend", capability.section()),
                backend: backend.name,
                reason,
            });
        }
    }
    let clock: Arc<dyn Clock> = Arc::new(RealClock::new());
    let vibrometer = open_ldv(&file.ldv, &clock)?;
    let daq = open_daq(&file.daq)?;
    let audio = open_audio(&file.audio)?;
    let keypad = file.keypad.as_ref().map(|keypad| open_keypad(keypad, &clock)).transpose()?;
    Ok(OpenedRig { rig: Rig { vibrometer, daq, audio, clock, wiring: file.wiring() }, keypad })
}

/// The error of an instrument that could not be opened.
fn device(capability: Capability, backend: &'static str, name: &str, detail: impl ToString) -> HardwareError {
    HardwareError::Device { device: capability.noun(), backend, name: name.to_string(), detail: detail.to_string() }
}

/// Reports a backend missing from this build as a device error; unreachable after `open_rig`'s check, and kept
/// so that every match below stays exhaustive whatever the features.
#[allow(dead_code)] // Used only in builds without some backend.
fn not_built(capability: Capability, backend: &'static str, name: &str) -> HardwareError {
    device(capability, backend, name, "this build of metaplate lacks the backend")
}

fn open_ldv(
    section: &LdvSection,
    clock: &Arc<dyn Clock>,
) -> Result<Box<dyn metaplate_core::vibrometer::Vibrometer + Send>, HardwareError> {
    match section {
        LdvSection::Serial(serial) => {
            let name = serial.port.display().to_string();
            #[cfg(feature = "serial")]
            {
                use metaplate_ldv::{LdvDriver, RetryPolicy, SerialPortLine};
                let error = |e: &dyn std::fmt::Display| device(Capability::Vibrometer, "serial", &name, e);
                let line = SerialPortLine::open(serial.selector()).map_err(|e| error(&e))?;
                let driver = LdvDriver::new(line, Arc::clone(clock), RetryPolicy::default()).map_err(|e| error(&e))?;
                Ok(Box::new(driver))
            }
            #[cfg(not(feature = "serial"))]
            {
                let _ = clock;
                Err(not_built(Capability::Vibrometer, "serial", &name))
            }
        }
    }
}

fn open_daq(section: &DaqSection) -> Result<Box<dyn metaplate_core::daq::Daq + Send>, HardwareError> {
    match section {
        DaqSection::UsbBulk(usb) => {
            #[cfg(feature = "usb-bulk")]
            {
                use metaplate_daq::{DaqDriver, DriverSettings, UsbTransport};
                let error = |e: &dyn std::fmt::Display| device(Capability::Daq, "usb-bulk", &usb.usb, e);
                let selector = usb.selector().map_err(|e| error(&e))?;
                let transport = UsbTransport::open(selector).map_err(|e| error(&e))?;
                let driver = DaqDriver::open(transport, DriverSettings::default()).map_err(|e| error(&e))?;
                Ok(Box::new(driver))
            }
            #[cfg(not(feature = "usb-bulk"))]
            Err(not_built(Capability::Daq, "usb-bulk", &usb.usb))
        }
        DaqSection::Nidaqmx(ni) => {
            #[cfg(feature = "nidaqmx")]
            {
                let daq = metaplate_daq::NiDaqmx::open(&ni.device, ni.read_timeout_s)
                    .map_err(|e| device(Capability::Daq, "nidaqmx", &ni.device, e))?;
                Ok(Box::new(daq))
            }
            #[cfg(not(feature = "nidaqmx"))]
            Err(not_built(Capability::Daq, "nidaqmx", &ni.device))
        }
    }
}

fn open_audio(section: &AudioSection) -> Result<Box<dyn metaplate_core::audio::AudioOut + Send>, HardwareError> {
    match section {
        AudioSection::Alsa(alsa) => {
            #[cfg(all(feature = "alsa", target_os = "linux"))]
            {
                use metaplate_audio::{AlsaSink, AudioDriver};
                use metaplate_core::audio::{AudioConfig, AudioOut};
                let mut audio = AudioDriver::new(AlsaSink::new(&alsa.device));
                audio
                    .configure(&AudioConfig { sample_rate_hz: alsa.sample_rate_hz, channels: alsa.channels })
                    .map_err(|e| device(Capability::Audio, "alsa", &alsa.device, e))?;
                Ok(Box::new(audio))
            }
            #[cfg(not(all(feature = "alsa", target_os = "linux")))]
            Err(not_built(Capability::Audio, "alsa", &alsa.device))
        }
    }
}

fn open_keypad(section: &KeypadSection, clock: &Arc<dyn Clock>) -> Result<Keypad<Box<dyn HidInput>>, HardwareError> {
    match section {
        KeypadSection::Hidraw(hid) => {
            #[cfg(all(feature = "hidraw", target_os = "linux"))]
            {
                use metaplate_keypad::{HidapiInput, HidapiSelector, ReportPrefix};
                let error = |e: &dyn std::fmt::Display| device(Capability::Keypad, "hidraw", &hid.usb, e);
                let ids = crate::file::UsbIds::parse(&hid.usb).map_err(|e| error(&e))?;
                let selector =
                    HidapiSelector { vendor_id: ids.vendor_id, product_id: ids.product_id, serial: ids.serial };
                let input: Box<dyn HidInput> = Box::new(HidapiInput::open(selector).map_err(|e| error(&e))?);
                let prefix = hid.report_id.map_or(ReportPrefix::None, ReportPrefix::ReportId);
                Ok(Keypad::new(input, Arc::clone(clock), prefix))
            }
            #[cfg(not(all(feature = "hidraw", target_os = "linux")))]
            {
                let _ = clock;
                Err(not_built(Capability::Keypad, "hidraw", &hid.usb))
            }
        }
    }
}
