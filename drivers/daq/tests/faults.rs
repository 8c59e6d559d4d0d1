//! Each injected fault: the driver recovers or reports a typed error, as specified. The mock never blocks, so
//! every test is bounded by the driver's retry and transfer bounds, not by time.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{mock_driver, two_channels};
use metaplate_core::daq::{Daq, DaqError};
use metaplate_daq::DaqDriver;
use metaplate_mock_daq::{Fault, FaultRates, FaultSchedule, MockTransport};

/// IN transfers a fresh driver makes before the first `configure` (open: GetInfo; the drain before it reads once).
fn reads_after_open() -> u64 {
    mock_driver(FaultSchedule::none()).transport().reads()
}

#[test]
fn short_stall_is_retried_and_the_late_reply_dropped() {
    // Stall the first read of `configure` (1 read): the attempt times out, the retry succeeds and the first
    // attempt's Ack, delivered late, is recognised as stale.
    let at = reads_after_open();
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 1 }));
    daq.configure(&two_channels()).unwrap();
    assert_eq!(daq.stats().retries, 1);
    assert_eq!(daq.stats().stale_replies, 1);
    assert!(daq.transport().device().config().is_some());
}

#[test]
fn long_stall_gives_a_timeout_after_the_retry_bound() {
    let at = reads_after_open();
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 1000 }));
    let err = daq.configure(&two_channels()).unwrap_err();
    // Settings allow 2 retries: 3 attempts.
    assert!(matches!(err, DaqError::Timeout { attempts: 3, .. }), "{err:?}");
    assert!(daq.transport().reads() - at < 20, "bounded: {} reads", daq.transport().reads() - at);
}

#[test]
fn stall_while_streaming_is_tolerated_up_to_the_bound() {
    let mut probe = mock_driver(FaultSchedule::none());
    probe.configure(&two_channels()).unwrap();
    probe.start().unwrap();
    probe.read_block().unwrap();
    let at = probe.transport().reads();
    // 2 quiet reads are within 2 retries: the block arrives, nothing is lost (the stall held the data).
    let mut daq2 = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 2 }));
    daq2.configure(&two_channels()).unwrap();
    daq2.start().unwrap();
    daq2.read_block().unwrap();
    let block = daq2.read_block().unwrap();
    assert_eq!(block.first_sample_index, 240);
    assert!(block.integrity.is_contiguous());
    // 3 quiet reads are one too many.
    let mut daq3 = mock_driver(FaultSchedule::none().at(at, Fault::Stall { reads: 3 }));
    daq3.configure(&two_channels()).unwrap();
    daq3.start().unwrap();
    daq3.read_block().unwrap();
    assert!(matches!(daq3.read_block(), Err(DaqError::Timeout { attempts: 3, .. })));
}

#[test]
fn disconnect_is_typed_and_reopen_reapplies_the_configuration() {
    let mut probe = mock_driver(FaultSchedule::none());
    probe.configure(&two_channels()).unwrap();
    probe.start().unwrap();
    let at = probe.transport().reads() + 3;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Disconnect));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let mut blocks = 0;
    let err = loop {
        match daq.read_block() {
            Ok(_) => blocks += 1,
            Err(e) => break e,
        }
        assert!(blocks < 10, "the disconnect must surface");
    };
    assert!(matches!(err, DaqError::Disconnected { .. }), "{err:?}");
    assert!(matches!(daq.stop(), Err(DaqError::Disconnected { .. })), "still off the bus");
    // The device power-cycled: it has forgotten its configuration until the driver re-applies it.
    assert!(daq.transport().device().config().is_none());
    daq.reopen().unwrap();
    assert_eq!(daq.transport().device().config(), daq.wire_config());
    assert!(daq.wire_config().is_some());
    assert!(!daq.transport().device().is_running());
    // A new acquisition starts from sample 0 without configuring again.
    daq.start().unwrap();
    let block = daq.read_block().unwrap();
    assert_eq!(block.first_sample_index, 0);
    assert!(block.integrity.is_contiguous());
    assert_eq!(daq.identity().serial, "SN0001");
    assert_eq!(daq.stats().reopens, 1);
}

#[test]
fn overrun_is_reported_on_the_block_after_the_gap() {
    let mut probe = mock_driver(FaultSchedule::none());
    probe.configure(&two_channels()).unwrap();
    probe.start().unwrap();
    let at = probe.transport().reads() + 2;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::Overrun { packets: 3 }));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let mut next = 0u64;
    let mut gaps = Vec::new();
    for _ in 0..6 {
        let block = daq.read_block().unwrap();
        if !block.integrity.is_contiguous() {
            gaps.push((block.first_sample_index, block.integrity));
        } else {
            assert_eq!(block.first_sample_index, next);
        }
        next = block.first_sample_index + block.len_samples() as u64;
    }
    assert_eq!(gaps.len(), 1, "{gaps:?}");
    let (first_sample_index, integrity) = gaps[0];
    assert!(integrity.overrun);
    assert_eq!(integrity.samples_missing, 3 * 240);
    assert_eq!(integrity.packets_lost, 0, "the device dropped samples; no packet was lost in transit");
    // The block's timestamp skips the lost samples instead of joining them.
    assert_eq!(first_sample_index % 240, 0);
    assert!(first_sample_index >= 4 * 240);
}

#[test]
fn fatal_overrun_ends_the_acquisition_with_a_typed_error() {
    let mut probe = mock_driver(FaultSchedule::none());
    probe.configure(&two_channels()).unwrap();
    probe.start().unwrap();
    let at = probe.transport().reads() + 2;
    let mut daq = mock_driver(FaultSchedule::none().at(at, Fault::FatalOverrun));
    daq.configure(&two_channels()).unwrap();
    daq.start().unwrap();
    let err = (0..10).find_map(|_| daq.read_block().err()).unwrap();
    assert!(matches!(err, DaqError::Overrun { .. }), "{err:?}");
    assert!(matches!(daq.read_block(), Err(DaqError::Protocol { .. })), "no acquisition runs");
    daq.start().unwrap();
    assert_eq!(daq.read_block().unwrap().first_sample_index, 0);
}

/// A recipe-like loop under a seeded fault schedule: reads 300 blocks; after an error it reopens (on a
/// disconnect), stops, re-applies the configuration and starts again, as the recipes' recovery does; it records
/// what happened.
fn run_seeded(seed: u64) -> Vec<String> {
    let rates = FaultRates { stall: 0.02, max_stall_reads: 4, disconnect: 0.01, overrun: 0.02 };
    let transport = MockTransport::new(common::sine_device(), FaultSchedule::seeded(seed, rates, 2000));
    let mut log = Vec::new();
    let mut daq = match DaqDriver::open(transport, common::settings()) {
        Ok(d) => d,
        Err(e) => return vec![format!("open: {e}")],
    };
    // A disconnect can hit any exchange, the first configuration's included: every failed step that says so is
    // followed by a reopen.
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
                reopen = matches!(e, DaqError::Disconnected { .. });
                log.push(format!("error {e:?}"));
                running = false;
            }
        }
    }
    log
}

#[test]
fn seeded_faults_are_deterministic() {
    let rates = FaultRates { stall: 0.02, max_stall_reads: 4, disconnect: 0.01, overrun: 0.02 };
    assert_eq!(FaultSchedule::seeded(7, rates, 2000), FaultSchedule::seeded(7, rates, 2000));
    assert_ne!(FaultSchedule::seeded(7, rates, 2000), FaultSchedule::seeded(8, rates, 2000));
    let schedule = FaultSchedule::seeded(7, rates, 2000);
    // 2000 draws at 5 % total: about 100 faults; +/-5 sigma (sigma ~ 9.7) keeps the check from being flaky while
    // still catching a rate that is ignored or misapplied.
    let n = schedule.events().len();
    assert!((50..=150).contains(&n), "{n} faults");
    let a = run_seeded(7);
    assert_eq!(a, run_seeded(7), "same seed, same run");
    assert!(a.iter().any(|l| l.starts_with("error")), "the schedule must hit the run: {a:?}");
    assert!(a.iter().any(|l| l.contains("overrun: true")), "an overrun must be reported");
    assert!(a.iter().any(|l| l == "recover true"), "the loop must recover");
}
