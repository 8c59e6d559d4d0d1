//! What `metaplate replay` prints of a replayed session: a summary a person reads ([`summary_text`]), the same as
//! one JSON object ([`ReplaySummary`]), and a cassette's records listed one a line ([`list_text`]).

use std::fmt::Write as _;

use metaplate_cassette::{Body, Cassette, Event};
use serde::Serialize;

use crate::faults::ReplayFaults;
use crate::load::LoadedCassette;
use crate::mismatch::escape;
use crate::session::SessionReport;

/// A replayed session as `replay --json` prints it. Fields in alphabetical order (the object's keys always were).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// DAQ blocks read.
    pub blocks: usize,
    /// Every driver call and how it ended.
    pub call_results: Vec<CallResult>,
    /// Driver calls.
    pub calls: usize,
    /// Blocks that clipped.
    pub clipped_blocks: usize,
    /// Whether the cassette's end marker was read.
    pub complete: bool,
    /// The device kind (`Ldv`, `Daq`, `Audio`).
    pub device: String,
    /// Calls that ended in an error.
    pub errors: usize,
    /// Driver writes matched against recorded ones.
    pub exchanges: usize,
    /// Faults given.
    pub faults: usize,
    /// Faults that fired.
    pub faults_fired: Vec<FaultFired>,
    /// Defects of the file (lenient loading).
    pub file_defects: Vec<String>,
    /// Whether every recorded call was played.
    pub finished: bool,
    /// The recorded device's identity.
    pub identity: IdentityJson,
    /// The driver's first deviation from the recording.
    pub mismatch: Option<String>,
    /// Blocks that overran.
    pub overrun_blocks: usize,
    /// Packets lost before the blocks.
    pub packets_lost: u64,
    /// Records in the cassette.
    pub records: usize,
    /// Resends answered again from the recording.
    pub resends_answered: usize,
    /// Retries the driver made.
    pub retries: u64,
    /// Samples missing before the blocks.
    pub samples_missing: u64,
    /// Replies made up for commands in no recorded exchange.
    pub synthesized: usize,
}

/// One driver call in [`ReplaySummary::call_results`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CallResult {
    /// The call.
    pub call: String,
    /// Whether it succeeded.
    pub ok: bool,
    /// Its value or error message.
    pub result: String,
}

/// A fault that fired.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FaultFired {
    /// Its kind's name.
    pub kind: &'static str,
    /// The record it fired on.
    pub record: usize,
}

/// The recorded device's identity.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IdentityJson {
    /// Model.
    pub model: String,
    /// Serial number.
    pub serial: String,
    /// Vendor.
    pub vendor: String,
}

impl ReplaySummary {
    /// The summary of `report`, a replay of `loaded` with `faults`.
    pub fn new(loaded: &LoadedCassette, faults: &ReplayFaults, report: &SessionReport) -> Self {
        let blocks = &report.blocks;
        let identity = &loaded.cassette.header.identity;
        Self {
            blocks: blocks.len(),
            call_results: report
                .calls
                .iter()
                .map(|c| CallResult {
                    call: c.call.clone(),
                    ok: c.result.is_ok(),
                    result: match &c.result {
                        Ok(v) | Err(v) => v.clone(),
                    },
                })
                .collect(),
            calls: report.calls.len(),
            clipped_blocks: blocks.iter().filter(|b| b.integrity.clipped).count(),
            complete: loaded.complete,
            device: format!("{:?}", report.device),
            errors: report.errors(),
            exchanges: report.stats.writes_matched,
            faults: faults.len(),
            faults_fired: report
                .stats
                .faults_applied
                .iter()
                .map(|(record, kind)| FaultFired { kind: kind.name(), record: *record })
                .collect(),
            file_defects: loaded.errors.iter().map(ToString::to_string).collect(),
            finished: report.finished,
            identity: IdentityJson {
                model: identity.model.clone(),
                serial: identity.serial.clone(),
                vendor: identity.vendor.clone(),
            },
            mismatch: report.mismatch.as_ref().map(ToString::to_string),
            overrun_blocks: blocks.iter().filter(|b| b.integrity.overrun).count(),
            packets_lost: blocks.iter().map(|b| b.integrity.packets_lost).sum(),
            records: report.records,
            resends_answered: report.stats.retries_replayed,
            retries: report.retries,
            samples_missing: blocks.iter().map(|b| b.integrity.samples_missing).sum(),
            synthesized: report.stats.synthesized,
        }
    }
}

/// The summary a person reads: the cassette, its records, the driver's calls, blocks, faults, and the verdict.
pub fn summary_text(loaded: &LoadedCassette, faults: &ReplayFaults, report: &SessionReport) -> String {
    let c = &loaded.cassette;
    let s = ReplaySummary::new(loaded, faults, report);
    let mut out = String::new();
    let id = &c.header.identity;
    let _ = writeln!(out, "cassette: {:?} {} {} serial {}", c.header.device_kind, id.vendor, id.model, id.serial);
    let _ = writeln!(
        out,
        "records: {} ({} calls, {} other), complete: {}",
        report.records, report.stats.steps, report.stats.ignored_records, loaded.complete
    );
    for e in &loaded.errors {
        let _ = writeln!(out, "file defect: {e}");
    }
    let _ = writeln!(out, "driver calls: {} ({} errors), retries: {}", s.calls, s.errors, report.retries);
    for call in &report.calls {
        let _ = match &call.result {
            Ok(v) => writeln!(out, "  {} -> {v}", call.call),
            Err(e) => writeln!(out, "  {} -> ERROR {e}", call.call),
        };
    }
    if s.blocks > 0 {
        let _ = writeln!(
            out,
            "blocks: {}, packets lost: {}, samples missing: {}, overrun blocks: {}, clipped blocks: {}",
            s.blocks, s.packets_lost, s.samples_missing, s.overrun_blocks, s.clipped_blocks
        );
    }
    let applied = &report.stats.faults_applied;
    let _ = writeln!(out, "faults: {} given, {} fired {:?}", faults.len(), applied.len(), applied);
    let _ = writeln!(
        out,
        "replay: {} exchanges matched, {} resends answered again, {} replies synthesized, finished: {}",
        s.exchanges, s.resends_answered, s.synthesized, report.finished
    );
    let _ = match &report.mismatch {
        Some(m) => writeln!(out, "MISMATCH: {m}"),
        None => writeln!(out, "ok: the driver did what the recording did"),
    };
    out
}

/// A record's content in a line.
fn describe(body: &Body) -> String {
    match body {
        Body::HostToDevice(b) => format!("host->device {}", escape(b)),
        Body::DeviceToHost(b) => format!("device->host {}", escape(b)),
        Body::Stream(s) => format!("stream {} frames x {} ch from {}", s.frames(), s.channels, s.first_sample_index),
        Body::Event(Event::Note(text)) => format!("note {text:?}"),
        Body::Event(e) => format!("event {}", e.name()),
    }
}

/// The cassette's header, then each record: index (what a fault names), time, endpoint, content.
pub fn list_text(cassette: &Cassette) -> String {
    let mut out = format!("{:?} {:?}\n", cassette.header.device_kind, cassette.header.identity);
    for (i, r) in cassette.records.iter().enumerate() {
        let _ = writeln!(out, "{i:5} {:>14.6} s  ep {}  {}", r.t_ns as f64 * 1e-9, r.endpoint, describe(&r.body));
    }
    out
}
