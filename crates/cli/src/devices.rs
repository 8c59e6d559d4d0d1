//! `metaplate devices`: what is connected that a hardware file can name, per instrument and backend (serial ports
//! with their USB ids, USB devices a bulk DAQ could be, NI-DAQmx devices where NI's library loads, ALSA playback
//! PCMs with their channel counts and rates, HID keyboards and keypads), and optionally a drafted hardware file.
//!
//! Nothing found is not an error: on a machine with none of them every list is empty and the exit code is 0.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use metaplate_drivers::{BACKENDS, Backend, Capability, Found, HardwareFile};
use serde_json::{Value, json};

/// Arguments of `metaplate devices`.
#[derive(Args)]
pub struct DevicesArgs {
    /// Print one JSON object on stdout instead of a list.
    #[arg(long)]
    json: bool,
    /// Draft a hardware file from what was found, with a comment on every line where the choice is yours (never
    /// overwrites: FILE must not exist).
    #[arg(long, value_name = "FILE")]
    write_hardware: Option<PathBuf>,
}

/// One backend's listing.
struct Listing {
    backend: &'static Backend,
    found: Vec<Found>,
    /// Why nothing could be listed: the build lacks the backend, or the system could not be asked.
    problem: Option<String>,
}

/// Runs `metaplate devices`.
pub fn run(args: &DevicesArgs) -> anyhow::Result<()> {
    let listings: Vec<Listing> = BACKENDS
        .iter()
        .map(|backend| match (backend.missing_reason(), backend.list()) {
            (Some(reason), _) => Listing { backend, found: Vec::new(), problem: Some(reason) },
            (None, Ok(found)) => Listing { backend, found, problem: None },
            (None, Err(e)) => Listing { backend, found: Vec::new(), problem: Some(e.to_string()) },
        })
        .collect();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&to_json(&listings))?);
    } else {
        print_listings(&listings);
    }
    if let Some(path) = &args.write_hardware {
        write_draft(path, &listings)?;
        if !args.json {
            println!("\ndrafted {}: check every line marked CHOOSE", path.display());
        }
    }
    Ok(())
}

fn to_json(listings: &[Listing]) -> Value {
    let mut out = serde_json::Map::new();
    for capability in Capability::ALL {
        let backends: Vec<Value> = listings
            .iter()
            .filter(|l| l.backend.capability == capability)
            .map(|l| {
                json!({
                    "backend": l.backend.name,
                    "in_this_build": l.backend.available,
                    "problem": l.problem,
                    "found": l.found.iter().map(|f| json!({"key": f.key, "value": f.value,
                        "description": f.description})).collect::<Vec<_>>(),
                })
            })
            .collect();
        out.insert(capability.section().to_owned(), json!(backends));
    }
    Value::Object(out)
}

fn print_listings(listings: &[Listing]) {
    for l in listings {
        let head = format!("{} ({})", l.backend.capability.noun(), l.backend.name);
        match (&l.problem, l.found.len()) {
            (Some(problem), _) => println!("{head}: not listed: {problem}"),
            (None, 0) => println!("{head}: none found"),
            (None, n) => println!("{head}: {n} found"),
        }
        for f in &l.found {
            println!("  {} = \"{}\"    {}", f.key, f.value, f.description);
        }
    }
}

/// The hardware file's line for `key`: the first value found, the others as comment lines; or `placeholder` with a
/// CHOOSE comment.
fn choose(listings: &[Listing], key: &str, placeholder: &str, what: &str) -> String {
    let found: Vec<&Found> = listings.iter().flat_map(|l| &l.found).filter(|f| f.key == key).collect();
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

/// Writes a hardware file drafted from `listings`; it must parse as a hardware file, and `path` must not exist.
fn write_draft(path: &Path, listings: &[Listing]) -> anyhow::Result<()> {
    if path.exists() {
        bail!("{} exists: a drafted hardware file never replaces one (choose another name)", path.display());
    }
    let mut text = String::from(
        "# A hardware file drafted by `metaplate devices --write-hardware` from what was connected. Lines marked\n\
         # CHOOSE need your decision; the format is documented in `cli/hardware.example.toml` and the\n\
         # metaplate-drivers crate.\n\n\
         plate = \"metamaterial\"   # CHOOSE: the scene describing your plate (built-in name or scene file)\n\n\
         [ldv]\nbackend = \"serial\"\n",
    );
    text.push_str(&choose(listings, "ldv.port", "/dev/ttyUSB0", "serial port"));
    text.push_str("baud = 115200\n\n[daq]\n");
    let nidaqmx = listings.iter().any(|l| l.found.iter().any(|f| f.key == "daq.device"));
    if nidaqmx {
        text.push_str("backend = \"nidaqmx\"   # CHOOSE: or \"usb-bulk\" with usb = \"VID:PID:SERIAL\"\n");
        text.push_str(&choose(listings, "daq.device", "Dev1", "NI-DAQmx device"));
    } else {
        text.push_str("backend = \"usb-bulk\"   # CHOOSE: or \"nidaqmx\" with device = \"Dev1\"\n");
        text.push_str(&choose(listings, "daq.usb", "1209:0001:SN0001", "USB device with a serial number"));
    }
    text.push_str("\n[audio]\nbackend = \"alsa\"\n");
    text.push_str(&choose(listings, "audio.device", "hw:CARD=24Ao,DEV=0", "ALSA playback PCM"));
    text.push_str(
        "sample_rate_hz = 48000.0   # CHECK: a rate the interface runs at exactly\n\
         channels = 9               # CHECK: at least the 8 actuators and the loopback\n\n",
    );
    let keypads: Vec<&Found> = listings.iter().flat_map(|l| &l.found).filter(|f| f.key == "keypad.usb").collect();
    text.push_str(
        "# Optional: the response keypad. CHOOSE: uncomment to use one.\n# [keypad]\n# backend = \"hidraw\"\n",
    );
    match keypads.first() {
        Some(k) => {
            let _ = writeln!(text, "# usb = \"{}\"   # found{}", k.value, described(k));
        }
        None => text.push_str("# usb = \"VID:PID\"   # no HID keyboard or keypad was found\n"),
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
    HardwareFile::parse(&text, path).context("internal: the drafted hardware file does not parse")?;
    // create_new: a file that appeared since the check above is not replaced either.
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .with_context(|| format!("creating {}", path.display()))?;
    std::io::Write::write_all(&mut file, text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
