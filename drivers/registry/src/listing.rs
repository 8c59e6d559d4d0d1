//! What is connected, per backend ([`list_connected`], what `metaplate devices` prints), and a hardware file
//! drafted from it ([`draft_hardware_file`], `metaplate devices --write-hardware`).
//!
//! Nothing found is not an error: on a machine with none of the instruments every list is empty.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::backends::{BACKENDS, Backend, Capability, Found};
use crate::file::{HardwareError, HardwareFile};

/// One backend's listing.
#[derive(Debug, Clone)]
pub struct Listing {
    /// The backend.
    pub backend: &'static Backend,
    /// What of it is connected.
    pub found: Vec<Found>,
    /// Why nothing could be listed: the build lacks the backend, or the system could not be asked.
    pub problem: Option<String>,
}

/// Every backend's listing, in the table's order.
pub fn list_connected() -> Vec<Listing> {
    BACKENDS
        .iter()
        .map(|backend| match (backend.missing_reason(), backend.list()) {
            (Some(reason), _) => Listing { backend, found: Vec::new(), problem: Some(reason) },
            (None, Ok(found)) => Listing { backend, found, problem: None },
            (None, Err(e)) => Listing { backend, found: Vec::new(), problem: Some(e.to_string()) },
        })
        .collect()
}

/// A listing as `devices --json` prints it (fields in alphabetical order, as the JSON always had them).
#[derive(Debug, Clone, Serialize)]
pub struct ListingJson {
    /// The backend's name.
    pub backend: &'static str,
    /// What is connected.
    pub found: Vec<FoundJson>,
    /// Whether this build has the backend.
    pub in_this_build: bool,
    /// Why nothing could be listed.
    pub problem: Option<String>,
}

/// A found device as `devices --json` prints it.
#[derive(Debug, Clone, Serialize)]
pub struct FoundJson {
    /// What the system says it is.
    pub description: String,
    /// The hardware file's key.
    pub key: &'static str,
    /// Its value.
    pub value: String,
}

/// The listings by capability section (`aim`, `audio`, `daq`, `keypad`, `ldv`), as `devices --json` prints them.
pub fn listings_json(listings: &[Listing]) -> BTreeMap<&'static str, Vec<ListingJson>> {
    Capability::ALL
        .iter()
        .map(|&capability| {
            let backends = listings
                .iter()
                .filter(|l| l.backend.capability == capability)
                .map(|l| ListingJson {
                    backend: l.backend.name,
                    found: l
                        .found
                        .iter()
                        .map(|f| FoundJson { description: f.description.clone(), key: f.key, value: f.value.clone() })
                        .collect(),
                    in_this_build: l.backend.available,
                    problem: l.problem.clone(),
                })
                .collect();
            (capability.section(), backends)
        })
        .collect()
}

/// The listings as lines a person reads: per backend a head line (found, none, or why not listed) and one line
/// per device with its hardware-file key.
pub fn listings_text(listings: &[Listing]) -> String {
    let mut text = String::new();
    for l in listings {
        let head = format!("{} ({})", l.backend.capability.noun(), l.backend.name);
        let _ = match (&l.problem, l.found.len()) {
            (Some(problem), _) => writeln!(text, "{head}: not listed: {problem}"),
            (None, 0) => writeln!(text, "{head}: none found"),
            (None, n) => writeln!(text, "{head}: {n} found"),
        };
        for f in &l.found {
            let _ = writeln!(text, "  {} = \"{}\"    {}", f.key, f.value, f.description);
        }
    }
    text
}

/// What the backend `backend` found for the hardware file's `key` (two backends may fill one key: an NI device's and
/// a capture PCM's are both `daq.device`).
fn found<'a>(listings: &'a [Listing], backend: &str, key: &str) -> Vec<&'a Found> {
    listings.iter().filter(|l| l.backend.name == backend).flat_map(|l| &l.found).filter(|f| f.key == key).collect()
}

/// The hardware file's line for `key`: the first value `backend` found, the others as comment lines; or
/// `placeholder` with a CHOOSE comment.
fn choose(listings: &[Listing], backend: &str, key: &str, placeholder: &str, what: &str) -> String {
    let found = found(listings, backend, key);
    let field = key.split('.').nth(1).unwrap_or(key);
    match found.split_first() {
        None => format!("{field} = \"{placeholder}\"   # CHOOSE: no {what} was found; put its name here\n"),
        Some((first, rest)) => {
            let verdict = if rest.is_empty() { "CHECK: the only one found" } else { "CHOOSE: the first of these" };
            let mut text = format!("{field} = \"{}\"   # {verdict}{}\n", first.value, described(first));
            for other in rest {
                let _ = writeln!(text, "# {field} = \"{}\"   # or this one{}", other.value, described(other));
            }
            text
        }
    }
}

/// ": description", or nothing when the system describes it not.
fn described(found: &Found) -> String {
    if found.description.is_empty() { String::new() } else { format!(": {}", found.description) }
}

/// A hardware file drafted from `listings`, with a comment on every line where the choice is the user's (CHOOSE,
/// CHECK); it parses as a hardware file (checked, naming `path` in errors).
///
/// # Errors
/// [`HardwareError`] if the draft does not parse (a bug).
pub fn draft_hardware_file(listings: &[Listing], path: &Path) -> Result<String, HardwareError> {
    let mut text = String::from(
        "# A hardware file drafted by `metaplate devices --write-hardware` from what was connected. Lines marked\n\
         # CHOOSE need your decision; the format is documented in `crates/cli/hardware.example.toml` and the\n\
         # metaplate-drivers crate.\n\n\
         plate = \"metamaterial\"   # CHOOSE: the scene describing your plate (built-in name or scene file)\n\n\
         [ldv]\nbackend = \"polytec\"\n",
    );
    text.push_str(&choose(listings, "polytec", "ldv.port", "/dev/ttyUSB0", "serial port"));
    text.push_str("baud = 115200\n\n[daq]\n");
    let ni_devices = found(listings, "nidaqmx", "daq.device");
    if ni_devices.is_empty() {
        text.push_str("backend = \"labjack-u6\"   # CHOOSE: or \"nidaqmx\" with device = \"Dev1\"\n");
        text.push_str(&choose(listings, "labjack-u6", "daq.serial", "360012345", "LabJack U6"));
    } else {
        text.push_str("backend = \"nidaqmx\"   # CHOOSE: or \"labjack-u6\" with serial = \"360012345\"\n");
        text.push_str(&choose(listings, "nidaqmx", "daq.device", "Dev1", "NI-DAQmx device"));
    }
    for pcm in found(listings, "alsa", "daq.device") {
        // The interface's own inputs can be the DAQ instead: named, not chosen (their full scale is the manual's).
        let _ = writeln!(
            text,
            "# or the audio interface's inputs: backend = \"alsa\", device = \"{}\"{}, full_scale_v = (its manual's)",
            pcm.value,
            described(pcm)
        );
    }
    text.push_str("\n[audio]\nbackend = \"alsa\"\n");
    text.push_str(&choose(listings, "alsa", "audio.device", "hw:CARD=24Ao,DEV=0", "ALSA playback PCM"));
    text.push_str(
        "sample_rate_hz = 48000.0   # CHECK: a rate the interface runs at exactly\n\
         channels = 9               # CHECK: at least the 8 actuators and the loopback\n\n",
    );
    let keypads = found(listings, "hidraw", "keypad.usb");
    text.push_str(
        "# Optional: the response keypad. CHOOSE: uncomment to use one.\n# [keypad]\n# backend = \"hidraw\"\n",
    );
    match keypads.first() {
        Some(k) => {
            let _ = writeln!(text, "# usb = \"{}\"   # found{}", k.value, described(k));
        }
        None => text.push_str("# usb = \"VID:PID\"   # no HID keyboard or keypad was found\n"),
    }
    if let Some(chain) = found(listings, "zaber", "aim.port").first() {
        // A Zaber chain answered: the stages as the aimer, commented out until the axes are checked.
        let _ = write!(
            text,
            "\n# Zaber stages answered{}. CHOOSE: uncomment to aim with them (see the user guide).\n\
             # [aim]\n# backend = \"zaber\"\n# port = \"{}\"\n# moves = \"head\"   # or \"plate\"\n\
             # [aim.x]\n# device = 1\n# microstep_um = 0.047625   # CHECK: the product's microstep size\n\
             # origin_mm = 50.0\n# [aim.y]\n# device = 2\n# microstep_um = 0.047625\n# origin_mm = 50.0\n",
            described(chain),
            chain.value
        );
    }
    if let Some(ni) = ni_devices.first() {
        // An NI device: galvo mirrors on two of its analog outputs, commented out until their map is taught.
        let _ = write!(
            text,
            "\n# NI-DAQmx device {value} found{}.\n\
             # CHOOSE: uncomment to aim galvo mirrors with two of its analog outputs, after teaching their map with\n\
             # `metaplate aim teach --hardware FILE`.\n\
             # [aim]\n# backend = \"galvo\"\n# fit = \"galvo-fit.toml\"   # written by `aim teach`, relative to this file\n\
             # settle_ms = 2.0\n# [aim.outputs]\n# backend = \"nidaqmx\"\n# device = \"{value}\"\n\
             # x_channel = \"ao0\"   # CHECK: the outputs cabled to the X and Y mirror drivers\n\
             # y_channel = \"ao1\"\n# limit_v = 10.0   # CHECK: the mirror drivers' input range, +/- V\n",
            described(ni),
            value = ni.value
        );
    }
    text.push_str(
        "\n[wiring]   # CHECK every line against the cabling\n\
         actuator_channels = [0, 1, 2, 3, 4, 5, 6, 7]   # audio channel of each actuator, in the plate's order\n\
         loopback_channel = 8                           # audio channel cabled back into the DAQ\n\
         velocity_input = 0                             # DAQ input of the LDV's velocity output\n\
         loopback_input = 1                             # DAQ input of the loopback\n\
         daq_range_v = 10.0                             # DAQ input range, +/- V\n\
         daq_sample_rate_hz = 24000.0\n\
         loopback_volts_per_full_scale = 1.0            # V at the DAQ for a full-scale audio sample\n",
    );
    HardwareFile::parse(&text, path)?;
    Ok(text)
}
