//! A U6 session recorded against the mock U6 (open, configure, start, blocks, stop), replayed through a fresh
//! `U6Driver` over `ReplayTransport`: clean, with faults the driver absorbs (stalls, a garbled response, a
//! refused write), with a dropped stream transfer it reports, and with a driver that deviates. Bounded in time: replay
//! and the in-process mock answer at once, and the driver's loops are bounded by its settings.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![allow(clippy::unwrap_used)]

use metaplate_cassette::{Body, Cassette};
use metaplate_core::daq::{Daq, DaqBlock, DaqError};
use metaplate_daq::{BulkTransport, DriverSettings, U6Driver};
use metaplate_replay::script::EP_STREAM;
use metaplate_replay::session::{DEMO_U6_SERIAL, demo_daq_config, record_mock_daq};
use metaplate_replay::{Deviation, FaultKind, ReplayFaults, ReplayTransport};
use metaplate_u6_protocol::{Command, StreamDecoder};

const BLOCKS: usize = 8;

/// What the session returned: identity, each call's result, every block in full.
#[derive(Debug, PartialEq)]
struct Results {
    identity: String,
    configure: Result<(), DaqError>,
    start: Result<(), DaqError>,
    blocks: Vec<Result<DaqBlock, DaqError>>,
    stop: Result<(), DaqError>,
}

fn session<T: BulkTransport>(daq: &mut U6Driver<T>) -> Results {
    let identity = format!("{:?}", daq.identity());
    let configure = daq.configure(&demo_daq_config());
    let start = daq.start();
    let blocks = (0..BLOCKS).map(|_| daq.read_block()).collect();
    let stop = daq.stop();
    Results { identity, configure, start, blocks, stop }
}

/// A one-line-per-call digest of results, for failure messages (full blocks would be megabytes of text).
fn digest(r: &Results) -> String {
    let blocks: Vec<String> = r
        .blocks
        .iter()
        .map(|b| match b {
            Ok(b) => format!("{}+{} {:?}", b.first_sample_index, b.volts[0].len(), b.integrity),
            Err(e) => format!("Err({e})"),
        })
        .collect();
    format!("configure {:?}, start {:?}, stop {:?}, blocks {blocks:#?}", r.configure, r.start, r.stop)
}

/// Asserts that two sessions' results are equal (block data included), printing digests if not.
fn assert_same(got: &Results, expected: &Results, context: &str) {
    assert!(got == expected, "{context}\ngot {}\nexpected {}", digest(got), digest(expected));
}

fn cassette() -> Cassette {
    let mut bytes = Vec::new();
    record_mock_daq(&mut bytes, BLOCKS).unwrap();
    Cassette::from_bytes(&bytes).unwrap()
}

fn replay(cassette: &Cassette, faults: ReplayFaults) -> (Results, U6Driver<ReplayTransport>) {
    let transport = ReplayTransport::new(cassette, faults).unwrap();
    let mut daq = U6Driver::open(transport, DriverSettings::default()).unwrap();
    (session(&mut daq), daq)
}

/// The clean replay's results: the reference, checked against the recording itself below.
fn reference(cassette: &Cassette) -> Results {
    let (results, daq) = replay(cassette, ReplayFaults::none());
    assert!(daq.transport().mismatch().is_none(), "{:?}", daq.transport().mismatch());
    results
}

/// Index of the record of the host's command of this kind (first one).
fn command_record(cassette: &Cassette, wanted: fn(&Command) -> bool) -> usize {
    cassette
        .records
        .iter()
        .position(|r| match &r.body {
            Body::HostToDevice(bytes) => Command::decode(bytes).is_ok_and(|c| wanted(&c)),
            _ => false,
        })
        .unwrap()
}

/// Index of the first device-to-host record after record `after`.
fn next_read(cassette: &Cassette, after: usize) -> usize {
    after + 1 + cassette.records[after + 1..].iter().position(|r| matches!(r.body, Body::DeviceToHost(_))).unwrap()
}

/// Indices of the records that carry stream data, with the StreamData packets each holds.
fn sample_records(cassette: &Cassette) -> Vec<(usize, usize)> {
    let spp = 24; // Two channels: 12 scans per packet.
    (0..cassette.records.len())
        .filter_map(|i| match (&cassette.records[i].body, cassette.records[i].endpoint) {
            (Body::DeviceToHost(bytes), EP_STREAM) => {
                let mut d = StreamDecoder::new(spp);
                d.push(bytes);
                let packets = std::iter::from_fn(|| d.poll()).filter(Result::is_ok).count();
                (packets > 0).then_some((i, packets))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn clean_replay_returns_the_recorded_blocks_exactly() {
    let mut bytes = Vec::new();
    let recorded = record_mock_daq(&mut bytes, BLOCKS).unwrap();
    let cassette = Cassette::from_bytes(&bytes).unwrap();
    let (results, daq) = replay(&cassette, ReplayFaults::none());
    assert!(results.configure.is_ok() && results.start.is_ok() && results.stop.is_ok(), "{results:?}");
    assert!(results.identity.contains(&DEMO_U6_SERIAL.to_string()), "{}", results.identity);
    // The replayed blocks are the recorded ones: same first scan, length and integrity, sample for sample
    // (exact: the same 16-bit codes go through the same calibration constants, read from the recording).
    assert_eq!(results.blocks.len(), recorded.len());
    for (block, summary) in results.blocks.iter().zip(&recorded) {
        let block = block.as_ref().unwrap();
        assert_eq!(block.first_sample_index, summary.first_sample_index);
        assert_eq!(block.volts[0].len(), summary.frames);
        assert_eq!(block.integrity, summary.integrity);
    }
    let transport = daq.transport();
    assert!(transport.mismatch().is_none() && transport.is_finished());
    assert_eq!(daq.stats().retries, 0);
    // And a second clean replay is identical to the first, block data included.
    assert_same(&reference(&cassette), &results, "second replay");
}

#[test]
fn a_stalled_reply_is_absorbed_by_the_drivers_retry() {
    let cassette = cassette();
    let expected = reference(&cassette);
    let configure = command_record(&cassette, |c| matches!(c, Command::StreamConfig(_)));
    let k = next_read(&cassette, configure);
    let (results, daq) = replay(&cassette, ReplayFaults::none().with(k, FaultKind::Stall));
    assert_same(&results, &expected, "");
    // The driver retried once (the same bytes again): the replay answered the resend from the recording.
    assert_eq!(daq.stats().retries, 1);
    assert_eq!(daq.transport().stats().retries_replayed, 1);
    assert_eq!(daq.transport().stats().faults_applied, vec![(k, FaultKind::Stall)]);
    assert!(daq.transport().mismatch().is_none() && daq.transport().is_finished());
}

#[test]
fn a_garbled_start_ack_and_a_refused_write_are_absorbed() {
    let cassette = cassette();
    let expected = reference(&cassette);
    let start = command_record(&cassette, |c| matches!(c, Command::StreamStart));
    // The last StreamStop: the session's `stop` (the first is the opening's).
    let stop = (0..cassette.records.len())
        .rev()
        .find(|&i| matches!(&cassette.records[i].body, Body::HostToDevice(b) if Command::decode(b) == Ok(Command::StreamStop)))
        .unwrap();
    for faults in [
        ReplayFaults::none().with(next_read(&cassette, start), FaultKind::Garble),
        ReplayFaults::none().with(start, FaultKind::Timeout),
        ReplayFaults::none().with(stop, FaultKind::Stall),
    ] {
        let (results, daq) = replay(&cassette, faults.clone());
        assert_same(&results, &expected, &format!("{faults:?}"));
        assert_eq!(daq.stats().retries, 1, "{faults:?}");
        assert!(daq.transport().mismatch().is_none(), "{faults:?}: {:?}", daq.transport().mismatch());
    }
}

#[test]
fn a_stall_in_the_stream_delays_but_loses_nothing() {
    let cassette = cassette();
    let expected = reference(&cassette);
    let k = sample_records(&cassette)[1].0;
    let (results, daq) = replay(&cassette, ReplayFaults::none().with(k, FaultKind::Stall));
    // `read_block` tolerates `retries` quiet reads; the late transfer then arrives whole.
    assert_same(&results, &expected, "");
    assert!(daq.transport().mismatch().is_none());
}

#[test]
fn a_dropped_stream_transfer_shows_in_the_next_blocks_integrity() {
    let cassette = cassette();
    let expected = reference(&cassette);
    let (record, packets) = sample_records(&cassette)[1];
    let (results, daq) = replay(&cassette, ReplayFaults::none().with(record, FaultKind::Drop));
    // The blocks before the gap are the recorded ones; the first block after it is charged with the transfer's
    // packets (PacketNumber gap) and their scans, and starts that many scans later than the recording went on.
    let gap = results.blocks.iter().position(|b| b.as_ref().is_ok_and(|b| !b.integrity.is_contiguous())).unwrap();
    assert_eq!(results.blocks[..gap - 1], expected.blocks[..gap - 1]);
    let after = results.blocks[gap].as_ref().unwrap();
    assert_eq!(after.integrity.packets_lost, packets as u64);
    assert_eq!(after.integrity.samples_missing, 12 * packets as u64);
    assert!(!after.integrity.overrun, "lost in transit, not at the source");
    let before = results.blocks[gap - 1].as_ref().unwrap();
    assert_eq!(
        after.first_sample_index,
        before.first_sample_index + before.volts[0].len() as u64 + 12 * packets as u64
    );
    // The session read one transfer short: a read_block at the end finds nothing and times out (typed), and the
    // session then stops as recorded.
    assert!(results.blocks.iter().any(|b| matches!(b, Err(DaqError::Timeout { .. }))), "{}", digest(&results));
    assert_eq!(results.stop, expected.stop);
    assert!(daq.transport().mismatch().is_none(), "{:?}", daq.transport().mismatch());
}

#[test]
fn a_driver_that_deviates_gets_the_mismatch() {
    let cassette = cassette();
    let transport = ReplayTransport::new(&cassette, ReplayFaults::none()).unwrap();
    let mut daq = U6Driver::open(transport, DriverSettings::default()).unwrap();
    let mut config = demo_daq_config();
    config.sample_rate_hz = 12_000.0;
    let err = daq.configure(&config).unwrap_err();
    assert!(matches!(&err, DaqError::Unavailable { detail } if detail.contains("replay mismatch")), "{err}");
    let m = daq.transport().mismatch().unwrap();
    assert_eq!(m.deviation, Deviation::Bytes);
    assert_eq!(m.record, command_record(&cassette, |c| matches!(c, Command::StreamConfig(_))));
    // 12 kHz on the 48 MHz clock is ScanInterval 4000 instead of 2000: the checksums (bytes 0, 4) differ first.
    assert_eq!(m.first_difference, Some(0));
}
