//! `metaplate replay`: re-run a recorded device session (a cassette) through its real driver, optionally with
//! faults injected; or record a short session against a mock device to try it.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use metaplate_cassette::{Body, Cassette, Event};
use metaplate_replay::session::{SessionReport, record_mock_daq, record_mock_ldv, replay};
use metaplate_replay::{LoadedCassette, ReplayFaults, escape, load_file};

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
        list(&loaded.cassette);
        return Ok(());
    }
    let report = replay(&loaded.cassette, faults.clone())?;
    if args.json {
        println!("{}", json(&loaded, &faults, &report));
    } else {
        print_summary(&loaded, &faults, &report);
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

fn describe(body: &Body) -> String {
    match body {
        Body::HostToDevice(b) => format!("host->device {}", escape(b)),
        Body::DeviceToHost(b) => format!("device->host {}", escape(b)),
        Body::Stream(s) => format!("stream {} frames x {} ch from {}", s.frames(), s.channels, s.first_sample_index),
        Body::Event(Event::Note(text)) => format!("note {text:?}"),
        Body::Event(e) => format!("event {}", e.name()),
    }
}

fn list(cassette: &Cassette) {
    println!("{:?} {:?}", cassette.header.device_kind, cassette.header.identity);
    for (i, r) in cassette.records.iter().enumerate() {
        println!("{i:5} {:>14.6} s  ep {}  {}", r.t_ns as f64 * 1e-9, r.endpoint, describe(&r.body));
    }
}

fn print_summary(loaded: &LoadedCassette, faults: &ReplayFaults, report: &SessionReport) {
    let c = &loaded.cassette;
    println!(
        "cassette: {:?} {} {} serial {}",
        c.header.device_kind, c.header.identity.vendor, c.header.identity.model, c.header.identity.serial
    );
    println!(
        "records: {} ({} calls, {} other), complete: {}",
        report.records, report.stats.steps, report.stats.ignored_records, loaded.complete
    );
    for e in &loaded.errors {
        println!("file defect: {e}");
    }
    println!("driver calls: {} ({} errors), retries: {}", report.calls.len(), report.errors(), report.retries);
    for call in &report.calls {
        match &call.result {
            Ok(v) => println!("  {} -> {v}", call.call),
            Err(e) => println!("  {} -> ERROR {e}", call.call),
        }
    }
    if !report.blocks.is_empty() {
        let lost: u64 = report.blocks.iter().map(|b| b.integrity.packets_lost).sum();
        let missing: u64 = report.blocks.iter().map(|b| b.integrity.samples_missing).sum();
        let overrun = report.blocks.iter().filter(|b| b.integrity.overrun).count();
        let clipped = report.blocks.iter().filter(|b| b.integrity.clipped).count();
        println!(
            "blocks: {}, packets lost: {lost}, samples missing: {missing}, overrun blocks: {overrun}, clipped \
            blocks: {clipped}",
            report.blocks.len()
        );
    }
    let applied = &report.stats.faults_applied;
    println!("faults: {} given, {} fired {:?}", faults.len(), applied.len(), applied);
    println!(
        "replay: {} exchanges matched, {} resends answered again, {} replies synthesized, finished: {}",
        report.stats.writes_matched, report.stats.retries_replayed, report.stats.synthesized, report.finished
    );
    match &report.mismatch {
        Some(m) => println!("MISMATCH: {m}"),
        None => println!("ok: the driver did what the recording did"),
    }
}

fn json(loaded: &LoadedCassette, faults: &ReplayFaults, report: &SessionReport) -> serde_json::Value {
    let blocks = &report.blocks;
    serde_json::json!({
        "device": format!("{:?}", report.device),
        "identity": {
            "vendor": loaded.cassette.header.identity.vendor,
            "model": loaded.cassette.header.identity.model,
            "serial": loaded.cassette.header.identity.serial,
        },
        "records": report.records,
        "complete": loaded.complete,
        "file_defects": loaded.errors.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "calls": report.calls.len(),
        "exchanges": report.stats.writes_matched,
        "errors": report.errors(),
        "call_results": report.calls.iter().map(|c| serde_json::json!({
            "call": c.call,
            "ok": c.result.is_ok(),
            "result": match &c.result { Ok(v) | Err(v) => v },
        })).collect::<Vec<_>>(),
        "retries": report.retries,
        "resends_answered": report.stats.retries_replayed,
        "synthesized": report.stats.synthesized,
        "faults": faults.len(),
        "faults_fired": report.stats.faults_applied.iter()
            .map(|(r, k)| serde_json::json!({"record": r, "kind": k.name()})).collect::<Vec<_>>(),
        "blocks": blocks.len(),
        "packets_lost": blocks.iter().map(|b| b.integrity.packets_lost).sum::<u64>(),
        "samples_missing": blocks.iter().map(|b| b.integrity.samples_missing).sum::<u64>(),
        "overrun_blocks": blocks.iter().filter(|b| b.integrity.overrun).count(),
        "clipped_blocks": blocks.iter().filter(|b| b.integrity.clipped).count(),
        "finished": report.finished,
        "mismatch": report.mismatch.as_ref().map(ToString::to_string),
    })
}
