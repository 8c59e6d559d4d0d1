//! Each injected fault: the driver recovers or reports a typed error, as specified. The mock never blocks, so
//! every test is bounded by the driver's retry and transfer bounds, not by time.

use crate::common;

use common::{SERIAL, mock_driver, two_channels};
use metaplate_core::daq::{Daq, DaqError};
use metaplate_daq::U6Driver;
use metaplate_mock_daq::{Fault, FaultRates, FaultSchedule, MockTransport};

/// IN transfers a fresh driver makes before the first `configure` (drains, StreamStop, ConfigU6, 4 ReadCal).
fn reads_after_open() -> u64 {
    mock_driver(FaultSchedule::none()).transport().reads()
}

/// IN transfers up to the first block of a fresh acquisition.
fn reads_at_first_block() -> u64 {
    let mut probe = mock_driver(FaultSchedule::none());
    probe.configure(&two_channels()).unwrap();
    probe.start().unwrap();
    probe.read_block().unwrap();
    probe.transport().reads()
}

#[test]
fn short_stall_is_retried_and_the_late_response_dropped() {
    // Stall the first read of `configure`: the attempt times out, the drain before the retry takes the held
    // response, the retry gets its own.
    let at = reads_after_open();
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 1 }));
    daq.configure(&two_channels()).unwrap();
    assert_eq!(daq.stats().retries, 1);
    assert!(daq.transport().device().config().is_some());
}

#[test]
fn long_stall_gives_a_timeout_after_the_retry_bound() {
    let at = reads_after_open();
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 1000 }));
    let err = daq.configure(&two_channels()).unwrap_err();
    // Settings allow 2 retries: 3 attempts.
    assert!(matches!(err, DaqError::Timeout { attempts: 3, .. }), "{err:?}");
    assert!(daq.transport().reads() - at < 40, "bounded: {} reads", daq.transport().reads() - at);
}

#[test]
fn stall_while_streaming_is_tolerated_up_to_the_bound() {
    let at = reads_at_first_block();
    // 2 quiet reads are within 2 retries: the data was held, nothing is lost.
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 2 }));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    daq.read_block().unwrap();
    let mut next = 240;
    for _ in 0..20 {
        let block = daq.read_block().unwrap();
        assert_eq!(block.first_sample_index, next);
        assert!(block.integrity.is_contiguous());
        next += 240;
    }
    // 3 quiet reads are one too many.
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 3 }));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    daq.read_block().unwrap();
    let err = (0..20).find_map(|_| daq.read_block().err()).unwrap();
    assert!(matches!(err, DaqError::Timeout { attempts: 3, .. }), "{err:?}");
}

#[test]
fn disconnect_is_typed_and_reopen_reapplies_the_configuration() {
    let at = reads_at_first_block() + 3;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Disconnect));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let err = (0..100).find_map(|_| daq.read_block().err()).unwrap();
    assert!(matches!(err, DaqError::Disconnected { .. }), "{err:?}");
    assert!(matches!(daq.stop(), Err(DaqError::Disconnected { .. })), "still off the bus");
    // The device power-cycled: it has forgotten its configuration until the driver re-applies it.
    assert!(daq.transport().device().config().is_none());
    daq.reopen().unwrap();
    assert_eq!(daq.transport().device().config(), daq.stream_config());
    assert!(daq.stream_config().is_some());
    assert!(!daq.transport().device().is_running());
    // A new acquisition starts from scan 0 without configuring again.
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    assert_eq!(block.first_sample_index, 0);
    assert!(block.integrity.is_contiguous());
    assert_eq!(daq.identity().serial, SERIAL.to_string());
    assert_eq!(daq.stats().reopens, 1);
}

/// Reads blocks until one is not contiguous; returns it with the index the blocks before it reached.
fn first_gap(daq: &mut U6Driver<MockTransport>) -> (u64, metaplate_core::daq::DaqBlock) {
    let mut next = 0u64;
    for _ in 0..50 {
        let block = daq.read_block().unwrap();
        if !block.integrity.is_contiguous() {
            return (next, block);
        }
        assert_eq!(block.first_sample_index, next);
        next = block.first_sample_index + block.len_samples() as u64;
    }
    panic!("no gap");
}

#[test]
fn an_auto_recovered_overflow_is_reported_on_the_block_after_the_gap() {
    let at = reads_at_first_block() + 2;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Overrun { scans: 30 }));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let (next, block) = first_gap(&mut daq);
    assert!(block.integrity.overrun);
    assert_eq!(block.integrity.packets_lost, 0, "the device discarded scans; no packet was lost in transit");
    // The block's timestamp skips the discarded scans instead of joining them.
    assert_eq!(block.first_sample_index, next + block.integrity.samples_missing);
    assert!(block.integrity.samples_missing >= 30);
    assert_eq!(daq.stats().stream.scans_discarded, 0, "counted when the stream ends");
    daq.stop().unwrap();
    assert_eq!(daq.stats().stream.scans_discarded, block.integrity.samples_missing);
    assert_eq!(daq.stats().stream.autorecover_packets, 1);
}

#[test]
fn a_packet_lost_in_transit_costs_its_scans() {
    let at = reads_at_first_block() + 1;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::DropPacket));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let (next, block) = first_gap(&mut daq);
    assert_eq!(block.integrity.packets_lost, 1);
    assert_eq!(block.integrity.samples_missing, 12, "one packet of 24 samples: 12 scans");
    assert!(!block.integrity.overrun);
    assert_eq!(block.first_sample_index, next + 12);
}

#[test]
fn an_overflow_beyond_counting_ends_the_acquisition_with_a_typed_error() {
    let at = reads_at_first_block() + 2;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::FatalOverrun));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let err = (0..50).find_map(|_| daq.read_block().err()).unwrap();
    assert!(
        matches!(&err, DaqError::Overrun { detail } if detail.contains("STREAM_AUTORECOVER_OVERFLOW (63)")),
        "{err:?}"
    );
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })), "no acquisition runs");
    daq.start().unwrap();
    assert_eq!(daq.read_block().unwrap().first_sample_index, 0);
}

fn rates() -> FaultRates {
    FaultRates { stall: 0.02, max_stall_reads: 4, disconnect: 0.01, overrun: 0.02, drop_packet: 0.01 }
}

/// A recipe-like loop under a seeded fault schedule: reads 300 blocks; after an error it reopens (on a
/// disconnect), stops, re-applies the configuration and starts again, as the recipes' recovery does; it records
/// what happened.
fn run_seeded(seed: u64) -> Vec<String> {
    let transport = MockTransport::new(common::sine_device(), FaultSchedule::none());
    let mut log = Vec::new();
    // Faults from after the opening exchanges (a disconnect there leaves nothing to recover).
    let mut daq = U6Driver::open(transport, common::settings()).unwrap();
    daq.transport_mut().set_faults(FaultSchedule::seeded(seed, rates(), 4000));
    let is_disconnect = |e: &DaqError| matches!(e, DaqError::Disconnected { .. });
    let first = daq.configure(&two_channels()).and_then(|()| daq.start());
    let mut reopen = first.as_ref().is_err_and(is_disconnect);
    let mut running = first.is_ok();
    for _ in 0..300 {
        if !running {
            if reopen {
                reopen = daq.reopen().is_err();
            }
            if !reopen {
                let restart = daq.stop().and_then(|()| daq.configure(&two_channels())).and_then(|()| daq.start());
                reopen = restart.as_ref().is_err_and(is_disconnect);
                running = restart.is_ok();
            }
            log.push(format!("recover {running}"));
            continue;
        }
        match daq.read_block() {
            Ok(b) => log.push(format!("{} {:?}", b.first_sample_index, b.integrity)),
            Err(e) => {
                reopen = is_disconnect(&e);
                log.push(format!("error {e:?}"));
                running = false;
            }
        }
    }
    log
}

#[test]
fn seeded_faults_are_deterministic() {
    assert_eq!(FaultSchedule::seeded(7, rates(), 2000), FaultSchedule::seeded(7, rates(), 2000));
    assert_ne!(FaultSchedule::seeded(7, rates(), 2000), FaultSchedule::seeded(8, rates(), 2000));
    // 2000 draws at 6 %: about 120 faults (sigma ~ 10.6); +/-5 sigma keeps the check from being flaky while still
    // catching a rate that is ignored or misapplied.
    let n = FaultSchedule::seeded(7, rates(), 2000).events().len();
    assert!((67..=173).contains(&n), "{n} faults");
    let a = run_seeded(7);
    assert_eq!(a, run_seeded(7), "same seed, same run");
    assert!(a.iter().any(|l| l.starts_with("error")), "the schedule must hit the run: {a:?}");
    assert!(a.iter().any(|l| l.contains("overrun: true")), "an overflow must be reported");
    assert!(a.iter().any(|l| l.contains("packets_lost: 1")), "a lost packet must be reported");
    assert!(a.iter().any(|l| l == "recover true"), "the loop must recover");
}
