//! `metaplate replay` end to end: record a session against each mock device, replay it clean and with faults,
//! and refuse damaged cassettes with a clear error.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common::{self, metaplate_bare as metaplate};

fn record(dir: &std::path::Path, device: &str) -> String {
    let path = dir.join(format!("{device}.cassette")).to_str().unwrap().to_owned();
    let out = metaplate(&["replay", "--record-mock", device, &path]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    path
}

fn replay_json(args: &[&str]) -> (bool, serde_json::Value) {
    let mut all = vec!["replay", "--json"];
    all.extend_from_slice(args);
    let out = metaplate(&all);
    let stdout = String::from_utf8(out.stdout).unwrap();
    (out.status.success(), serde_json::from_str(stdout.trim()).unwrap())
}

/// The record index of the first record whose `--list` line contains `needle`.
fn record_index(path: &str, needle: &str) -> usize {
    let out = metaplate(&["replay", "--list", path]);
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text.lines().find(|l| l.contains(needle)).unwrap();
    line.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn an_ldv_session_replays_clean_and_absorbs_a_timeout() {
    let dir = common::scratch("replay-cli", "replay-ldv");
    let path = record(&dir, "ldv");
    let (ok, clean) = replay_json(&[&path]);
    assert!(ok, "{clean}");
    assert_eq!(clean["device"], "LdvSerial");
    assert_eq!(clean["errors"], 0);
    assert_eq!(clean["finished"], true);
    assert!(clean["mismatch"].is_null());
    // The reply to the signal-level query (the record after `Get,SignalLevel,0,Value`), timed out: the driver
    // discards what is waiting and resends, and the session ends with the same results.
    let k = record_index(&path, "host->device \"Get,SignalLevel") + 1;
    let (ok, faulted) = replay_json(&["--fault", &format!("timeout@{k}"), &path]);
    assert!(ok, "{faulted}");
    assert_eq!(faulted["call_results"], clean["call_results"]);
    assert_eq!(faulted["resends_answered"], 1);
    assert_eq!(faulted["faults_fired"][0]["record"], k);
    // Human-readable output too.
    let out = metaplate(&["replay", &path]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(out.status.success() && text.contains("ok: the driver did what the recording did"), "{text}");
}

#[test]
fn a_daq_session_replays_with_a_dropped_packet_reported() {
    let dir = common::scratch("replay-cli", "replay-daq");
    let path = record(&dir, "daq");
    let (ok, clean) = replay_json(&[&path]);
    assert!(ok, "{clean}");
    let clean_blocks = clean["blocks"].as_u64().unwrap();
    assert!(clean_blocks > 0 && clean["packets_lost"].as_u64() == Some(0), "{clean}");
    // Drop the 3rd stream transfer (the U6's stream endpoint, 3): 240 scans of the recording's blocks, in 20
    // packets of 12 scans (two channels, 25 samples a packet at most).
    let out = String::from_utf8(metaplate(&["replay", "--list", &path]).stdout).unwrap();
    let k: usize = out
        .lines()
        .filter(|l| l.contains("ep 3  device->host"))
        .nth(2)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let (ok, dropped) = replay_json(&["--fault", &format!("drop@{k}"), &path]);
    assert!(ok, "{dropped}");
    // The transfer's 20 packets lost, shown in the integrity of the next block; the replay reads while the
    // recording read, so it gets their 20 blocks fewer.
    assert_eq!(dropped["packets_lost"].as_u64(), Some(20), "{dropped}");
    assert_eq!(dropped["blocks"].as_u64(), Some(clean_blocks - 20), "{dropped}");
    assert_eq!(dropped["samples_missing"], 240);
}

#[test]
fn damaged_cassettes_and_bad_faults_are_clear_errors() {
    let dir = common::scratch("replay-cli", "replay-bad");
    let path = record(&dir, "ldv");
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.join("cut.cassette");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = metaplate(&["replay", cut.to_str().unwrap()]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success() && err.contains("truncated") && !err.contains("panicked"), "{err}");
    // The defect is said once (it was repeated as the error and as its source).
    assert_eq!(err.matches("cassette truncated").count(), 1, "{err}");
    assert!(err.contains(": bad cassette: cassette truncated after "), "{err}");
    // Lenient: the exchanges before the cut replay, and the summary names the defect.
    let out = metaplate(&["replay", "--lenient", cut.to_str().unwrap()]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(out.status.success() && text.contains("file defect: cassette truncated"), "{text}");
    let junk = dir.join("junk.cassette");
    std::fs::write(&junk, b"not a cassette at all").unwrap();
    let out = metaplate(&["replay", junk.to_str().unwrap()]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success() && err.contains("magic") && !err.contains("panicked"), "{err}");
    let out = metaplate(&["replay", "--fault", "melt@3", &path]);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success() && err.contains("KIND@RECORD"), "{err}");
}
