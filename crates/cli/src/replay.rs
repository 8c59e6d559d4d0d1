//! `metaplate replay`: re-run a recorded device session (a cassette) through its real driver, optionally with
//! faults injected; or record a short session against a mock device to try it. What it prints is the replay
//! crate's ([`metaplate_replay::summary`]).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use metaplate_replay::session::{record_mock_daq, record_mock_ldv, replay};
use metaplate_replay::{ReplayFaults, ReplaySummary, list_text, load_file, summary_text};

/// A mock device to record a demo session against.
#[derive(Clone, Copy, ValueEnum)]
pub enum MockKind {
    /// The scanning LDV's controller (serial line).
    Ldv,
    /// The DAQ (USB bulk).
    Daq,
}

/// Arguments of `metaplate replay`.
#[derive(Args)]
pub struct ReplayArgs {
    /// The cassette to replay (or, with --record-mock, to write).
    cassette: PathBuf,
    /// Inject a fault, KIND@RECORD (kinds: timeout, stall, drop, garble, truncate, disconnect; RECORD is the
    /// record index that --list shows). Repeatable.
    #[arg(long = "fault", value_name = "SPEC")]
    faults: Vec<String>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
    /// List the cassette's records (index, time, endpoint, content) instead of replaying.
    #[arg(long)]
    list: bool,
    /// Replay a damaged or cut-short cassette up to its defects instead of refusing it.
    #[arg(long)]
    lenient: bool,
    /// Record a short session against this mock device into CASSETTE instead of replaying.
    #[arg(long, value_enum, value_name = "DEVICE")]
    record_mock: Option<MockKind>,
}

/// Blocks read in the DAQ demo recording.
const DEMO_BLOCKS: usize = 8;

pub fn run(args: &ReplayArgs) -> anyhow::Result<()> {
    if let Some(kind) = args.record_mock {
        return record(kind, args);
    }
    let faults = ReplayFaults::parse(&args.faults)?;
    let loaded = load_file(&args.cassette, !args.lenient)
        .with_context(|| format!("cannot replay {}", args.cassette.display()))?;
    if args.list {
        print!("{}", list_text(&loaded.cassette));
        return Ok(());
    }
    let report = replay(&loaded.cassette, faults.clone())?;
    if args.json {
        println!("{}", serde_json::to_string(&ReplaySummary::new(&loaded, &faults, &report))?);
    } else {
        print!("{}", summary_text(&loaded, &faults, &report));
    }
    if let Some(m) = &report.mismatch {
        bail!("{m}");
    }
    Ok(())
}

fn record(kind: MockKind, args: &ReplayArgs) -> anyhow::Result<()> {
    let path = &args.cassette;
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut out = std::io::BufWriter::new(file);
    let what = match kind {
        MockKind::Ldv => format!("{} LDV calls", record_mock_ldv(&mut out)?.len()),
        MockKind::Daq => format!("{} DAQ blocks", record_mock_daq(&mut out, DEMO_BLOCKS)?.len()),
    };
    let file = out.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()?;
    println!("recorded {what} from the mock device into {}", path.display());
    Ok(())
}
