//! `metaplate devices`: what is connected that a hardware file can name, per instrument and backend (serial ports
//! with their USB ids, USB devices a bulk DAQ could be, NI-DAQmx devices where NI's library loads, ALSA playback
//! PCMs with their channel counts and rates, HID keyboards and keypads), and optionally a drafted hardware file
//! (the driver registry lists and drafts: [`metaplate_drivers::listing`]).
//!
//! Nothing found is not an error: on a machine with none of them every list is empty and the exit code is 0.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_drivers::{draft_hardware_file, list_connected, listings_json, listings_text};

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

/// Runs `metaplate devices`.
pub fn run(args: &DevicesArgs) -> anyhow::Result<()> {
    let listings = list_connected();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&listings_json(&listings))?);
    } else {
        print!("{}", listings_text(&listings));
    }
    if let Some(path) = &args.write_hardware {
        if path.exists() {
            bail!("{} exists: a drafted hardware file never replaces one (choose another name)", path.display());
        }
        let text =
            draft_hardware_file(&listings, path).context("internal: the drafted hardware file does not parse")?;
        // create_new: a file that appeared since the check above is not replaced either.
        let mut file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .with_context(|| format!("creating {}", path.display()))?;
        file.write_all(text.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        if !args.json {
            println!("\ndrafted {}: check every line marked CHOOSE", path.display());
        }
    }
    Ok(())
}
