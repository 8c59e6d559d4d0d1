//! One table of backends per capability: each backend's name in the hardware file, what it needs, whether this
//! build has it, and what of it is connected (for `metaplate devices`).

/// An instrument's capability, as the hardware file's sections name them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Capability {
    /// `[ldv]`: the scanning vibrometer ([`metaplate_core::vibrometer::Vibrometer`]).
    Vibrometer,
    /// `[daq]`: the DAQ ([`metaplate_core::daq::Daq`]).
    Daq,
    /// `[audio]`: the audio interface ([`metaplate_core::audio::AudioOut`]).
    Audio,
    /// `[keypad]`: the response keypad (optional; beside the rig, not in it).
    Keypad,
    /// `[aim]`: what puts the beam on a point ([`metaplate_core::aim::Aim`]; optional: without it every point is
    /// refused).
    Aim,
}

impl Capability {
    /// Every capability, in the hardware file's order.
    pub const ALL: [Capability; 5] =
        [Capability::Vibrometer, Capability::Daq, Capability::Audio, Capability::Keypad, Capability::Aim];

    /// Its section in the hardware file.
    pub fn section(self) -> &'static str {
        match self {
            Capability::Vibrometer => "ldv",
            Capability::Daq => "daq",
            Capability::Audio => "audio",
            Capability::Keypad => "keypad",
            Capability::Aim => "aim",
        }
    }

    /// The instrument, as messages name it.
    pub fn noun(self) -> &'static str {
        match self {
            Capability::Vibrometer => "LDV",
            Capability::Daq => "DAQ",
            Capability::Audio => "audio interface",
            Capability::Keypad => "keypad",
            Capability::Aim => "aimer",
        }
    }
}

/// Something connected that a backend could open, with what the hardware file writes to name it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    /// The key to set (`ldv.port`, `daq.serial`).
    pub key: &'static str,
    /// Its value (`/dev/ttyUSB0`, `360012345`).
    pub value: String,
    /// What the system says it is (manufacturer, product), empty when it says nothing.
    pub description: String,
}

/// Why a backend could not list what is connected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("cannot list {backend} devices: {detail}")]
pub struct ListError {
    /// The backend.
    pub backend: &'static str,
    /// The system's reason.
    pub detail: String,
}

/// One backend of a capability.
#[derive(Debug, Clone, Copy)]
pub struct Backend {
    /// Its capability.
    pub capability: Capability,
    /// Its name in the hardware file (`backend = "..."`).
    pub name: &'static str,
    /// What it needs, in a sentence (keys of its section, system libraries, permissions).
    pub needs: &'static str,
    /// The cargo feature of `metaplate-drivers` (and of the binary) that builds it.
    pub feature: &'static str,
    /// Whether this build has it.
    pub available: bool,
    /// Whether it exists on Linux only (`alsa`, `hidraw`).
    pub linux_only: bool,
    list: fn() -> Result<Vec<Found>, ListError>,
}

impl Backend {
    /// Why this build lacks it and how to get it, or `None` when it has it.
    pub fn missing_reason(&self) -> Option<String> {
        if self.available {
            None
        } else if self.linux_only && !cfg!(target_os = "linux") {
            Some(format!("the {} backend exists on Linux only, and this is {}", self.name, std::env::consts::OS))
        } else {
            Some(format!(
                "this build of metaplate lacks it: rebuild with the cargo feature `{}` (the binary's default \
                 `hardware` feature has every backend)",
                self.feature
            ))
        }
    }

    /// What of this backend is connected. Empty when nothing is and when this build lacks the backend (and for
    /// `nidaqmx` when NI-DAQmx is not installed).
    ///
    /// # Errors
    /// [`ListError`] when the system cannot be asked (the bus cannot be read).
    pub fn list(&self) -> Result<Vec<Found>, ListError> {
        if self.available { (self.list)() } else { Ok(Vec::new()) }
    }
}

/// Every backend of every capability.
pub const BACKENDS: [Backend; 9] = [
    Backend {
        capability: Capability::Vibrometer,
        name: "polytec",
        needs: "a Polytec controller's RS-232 port (`port`), read and write access to it; optionally the decoder \
                (`decoder = \"VD-09\"` or an index)",
        feature: "serial",
        available: cfg!(feature = "serial"),
        linux_only: false,
        list: list_serial,
    },
    Backend {
        capability: Capability::Vibrometer,
        name: "analog",
        needs: "the range set at the instrument (`range = \"25mm/s/V\"`), its `vendor` and `model`; nothing is sent",
        feature: "(none: always built)",
        available: true,
        linux_only: false,
        list: list_nothing,
    },
    Backend {
        capability: Capability::Daq,
        name: "labjack-u6",
        needs: "a LabJack U6 on USB (`serial = \"360012345\"`, as on its label), access to its USB device",
        feature: "labjack-u6",
        available: cfg!(feature = "labjack-u6"),
        linux_only: false,
        list: list_usb,
    },
    Backend {
        capability: Capability::Daq,
        name: "nidaqmx",
        needs: "NI-DAQmx installed (the vendor library is loaded at run time) and the NI device name (`device`)",
        feature: "nidaqmx",
        available: cfg!(feature = "nidaqmx"),
        linux_only: false,
        list: list_nidaqmx,
    },
    Backend {
        capability: Capability::Daq,
        name: "alsa",
        needs: "a sound card's capture PCM (`device`, as `arecord -L` names it) at an exact rate, and its inputs' \
                voltage at full scale (`full_scale_v`, from its manual)",
        feature: "alsa",
        available: cfg!(all(feature = "alsa", target_os = "linux")),
        linux_only: true,
        list: list_alsa_capture,
    },
    Backend {
        capability: Capability::Audio,
        name: "alsa",
        needs: "an ALSA PCM (`device`, as `aplay -L` names it) at an exact rate and channel count",
        feature: "alsa",
        available: cfg!(all(feature = "alsa", target_os = "linux")),
        linux_only: true,
        list: list_alsa,
    },
    Backend {
        capability: Capability::Keypad,
        name: "hidraw",
        needs: "a USB HID keyboard (`usb = \"VID:PID[:SERIAL]\"`), read access to its /dev/hidraw node",
        feature: "hidraw",
        available: cfg!(all(feature = "hidraw", target_os = "linux")),
        linux_only: true,
        list: list_hidraw,
    },
    Backend {
        capability: Capability::Aim,
        name: "galvo",
        needs: "galvanometer mirrors on two analog outputs (`[aim.outputs]`: `backend = \"nidaqmx\"`, `device`, \
                `x_channel`, `y_channel`), the fit `metaplate aim teach` writes (`fit`), the settling time \
                (`settle_ms`)",
        feature: "(none: always built; its outputs need theirs)",
        available: true,
        linux_only: false,
        list: list_nothing,
    },
    Backend {
        capability: Capability::Aim,
        name: "zaber",
        needs: "Zaber stages on a serial port (`port`, `moves = \"head\"` or `\"plate\"`), and per axis (`[aim.x]`, \
                `[aim.y]`) the `device`, `axis`, the product's `microstep_um` and the plate's `origin_mm`",
        feature: "zaber",
        available: cfg!(feature = "zaber"),
        linux_only: false,
        list: list_zaber,
    },
];

/// The backends of `capability`.
pub fn of(capability: Capability) -> impl Iterator<Item = &'static Backend> {
    BACKENDS.iter().filter(move |b| b.capability == capability)
}

/// The backend of `capability` named `name`, if there is one.
pub fn find(capability: Capability, name: &str) -> Option<&'static Backend> {
    of(capability).find(|b| b.name == name)
}

/// The names of `capability`'s backends.
pub(crate) fn names(capability: Capability) -> Vec<&'static str> {
    of(capability).map(|b| b.name).collect()
}

/// For a backend that has nothing to list (`analog`), or that this build lacks (never called then:
/// [`Backend::list`] checks `available` first).
fn list_nothing() -> Result<Vec<Found>, ListError> {
    Ok(Vec::new())
}

/// NI-DAQmx devices by their NI names, with product type and serial number; none when NI-DAQmx is not installed
/// (not an error: the backend is there, the vendor library is not).
#[cfg(feature = "nidaqmx")]
fn list_nidaqmx() -> Result<Vec<Found>, ListError> {
    let devices =
        metaplate_daq::nidaqmx_devices().map_err(|e| ListError { backend: "nidaqmx", detail: e.to_string() })?;
    Ok(devices
        .unwrap_or_default()
        .into_iter()
        .map(|d| Found {
            key: "daq.device",
            value: d.name,
            description: format!("NI {} s/n {:08X}", d.product_type, d.serial),
        })
        .collect())
}

#[cfg(not(feature = "nidaqmx"))]
fn list_nidaqmx() -> Result<Vec<Found>, ListError> {
    list_nothing()
}

/// ALSA playback PCMs with the channel counts and rates they accept.
fn list_alsa() -> Result<Vec<Found>, ListError> {
    list_pcms(true)
}

/// ALSA capture PCMs with the channel counts and rates they accept.
fn list_alsa_capture() -> Result<Vec<Found>, ListError> {
    list_pcms(false)
}

#[cfg(all(feature = "alsa", target_os = "linux"))]
fn list_pcms(playback: bool) -> Result<Vec<Found>, ListError> {
    let (pcms, key) = if playback {
        (metaplate_audio::playback_pcms(), "audio.device")
    } else {
        (metaplate_audio::capture_pcms(), "daq.device")
    };
    let pcms = pcms.map_err(|e| ListError { backend: "alsa", detail: e.to_string() })?;
    Ok(pcms
        .into_iter()
        .map(|pcm| {
            let ranges = match (pcm.channels, pcm.rates_hz) {
                (Some((c0, c1)), Some((r0, r1))) => format!("{c0} to {c1} channels, {r0} to {r1} Hz"),
                _ => pcm.note,
            };
            Found { key, value: pcm.name, description: format!("{}: {ranges}", pcm.card) }
        })
        .collect())
}

#[cfg(not(all(feature = "alsa", target_os = "linux")))]
fn list_pcms(_playback: bool) -> Result<Vec<Found>, ListError> {
    list_nothing()
}

/// HID devices with a keyboard or keypad collection.
#[cfg(all(feature = "hidraw", target_os = "linux"))]
fn list_hidraw() -> Result<Vec<Found>, ListError> {
    let pads = metaplate_keypad::keypads().map_err(|e| ListError { backend: "hidraw", detail: e.to_string() })?;
    Ok(pads.into_iter().map(|p| Found { key: "keypad.usb", value: p.usb, description: p.description }).collect())
}

#[cfg(not(all(feature = "hidraw", target_os = "linux")))]
fn list_hidraw() -> Result<Vec<Found>, ListError> {
    list_nothing()
}

#[cfg(feature = "serial")]
fn list_serial() -> Result<Vec<Found>, ListError> {
    let ports =
        metaplate_ldv::available_ports().map_err(|e| ListError { backend: "polytec", detail: e.to_string() })?;
    Ok(ports
        .into_iter()
        .map(|port| {
            let usb = port.usb_ids.map(|(vid, pid)| match &port.usb_serial {
                Some(serial) => format!("USB {vid:04x}:{pid:04x} serial {serial}"),
                None => format!("USB {vid:04x}:{pid:04x}"),
            });
            // A Polytec controller names itself when asked (`GetDevInfo,Controller,0,Name`); a port that cannot be
            // opened (busy, no permission) or does not answer is listed without it.
            let polytec = metaplate_ldv::SerialPortLine::open(metaplate_ldv::PortSelector::Path(port.path.clone()))
                .ok()
                .and_then(|line| metaplate_ldv::probe_polytec(line, 0.3).ok())
                .map(|name| format!("Polytec {name}"));
            let description =
                [polytec.unwrap_or_default(), usb.unwrap_or_default(), port.description].join(" ").trim().to_string();
            Found { key: "ldv.port", value: port.path.display().to_string(), description }
        })
        .collect())
}

#[cfg(not(feature = "serial"))]
fn list_serial() -> Result<Vec<Found>, ListError> {
    Ok(Vec::new())
}

/// Serial ports where a Zaber chain answers, with its devices.
#[cfg(feature = "zaber")]
fn list_zaber() -> Result<Vec<Found>, ListError> {
    let chains = crate::zaber::chains_on_serial_ports().map_err(|detail| ListError { backend: "zaber", detail })?;
    Ok(chains.into_iter().map(|(value, description)| Found { key: "aim.port", value, description }).collect())
}

#[cfg(not(feature = "zaber"))]
fn list_zaber() -> Result<Vec<Found>, ListError> {
    list_nothing()
}

/// The LabJack U6s on USB (vendor `0x0CD5`, product `0x0006`), by the serial number of their USB descriptor.
#[cfg(feature = "labjack-u6")]
fn list_usb() -> Result<Vec<Found>, ListError> {
    use metaplate_u6_protocol::{PRODUCT_ID, VENDOR_ID};
    let devices =
        metaplate_daq::usb_devices().map_err(|e| ListError { backend: "labjack-u6", detail: e.to_string() })?;
    Ok(devices
        .into_iter()
        .filter(|d| (d.vendor_id, d.product_id) == (VENDOR_ID, PRODUCT_ID))
        .map(|d| match d.serial {
            Some(serial) => Found { key: "daq.serial", value: serial, description: d.description },
            None => Found {
                key: "daq.serial",
                value: "?".into(),
                description: "a LabJack U6 whose USB descriptor has no serial number: read it from its label".into(),
            },
        })
        .collect())
}

#[cfg(not(feature = "labjack-u6"))]
fn list_usb() -> Result<Vec<Found>, ListError> {
    Ok(Vec::new())
}
