//! The stage driver against the mock chain in process, on a virtual clock (moves cost no wall time).

use std::sync::Arc;

use metaplate_aim::zaber::{MovingPart, ZaberError, ZaberStages};
use metaplate_core::aim::{Aim, AimError};
use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_mock_zaber::{ArmedFault, ChainLine};
use metaplate_zaber_protocol::WarningFlag;

use crate::common::{ORIGIN_MM, chain, config, host_lines, us};

const SPEED_MM_PER_S: f64 = 20.0;

fn position(chain: &std::sync::Mutex<metaplate_mock_zaber::MockChain>, device: u8) -> Option<i64> {
    chain.lock().ok()?.position_us(device, 1)
}

#[test]
fn opening_homes_unreferenced_axes_and_moves_go_in_mm() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let stages = ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain.clone()), clock.clone());
    let Ok(mut stages) = stages else { panic!("open failed: {stages:?}") };
    // Both axes were at 50 mm unreferenced (`WR`): homing took 50 mm / 20 mm/s.
    assert!(host_lines(&chain).iter().filter(|l| l.ends_with(" home")).count() == 2);
    assert!(clock.now_s() >= 2.5 && clock.now_s() < 2.6, "homing took {} s", clock.now_s());
    assert_eq!((position(&chain, 1), position(&chain, 2)), (Some(0), Some(0)));

    // The head moves: plate (10 mm, -20 mm) is the stages at 60 mm and 30 mm.
    let before_s = clock.now_s();
    assert_eq!(stages.aim_at(0.010, -0.020), Ok(()));
    assert_eq!(position(&chain, 1), Some(us(ORIGIN_MM + 10.0)));
    assert_eq!(position(&chain, 2), Some(us(ORIGIN_MM - 20.0)));
    // The longer move, 60 mm at 20 mm/s, is what the aimer waited for (polls every 10 ms).
    let waited_s = clock.now_s() - before_s;
    assert!((3.0..3.05).contains(&waited_s), "waited {waited_s} s");
    let Ok((x_m, y_m)) = stages.position_m() else { panic!("no position") };
    // One microstep is 0.05 µm: the read-back is the target within it.
    assert!((x_m - 0.010).abs() < 1e-7 && (y_m + 0.020).abs() < 1e-7, "({x_m}, {y_m})");
    // The rig record names the stages by device and axis, never by the pseudo-terminal's changing path.
    let described = stages.describe();
    assert!(
        described.starts_with("Zaber stages moving the head: x device 1 axis 1 (0.000 to 100.000 mm)"),
        "{described}"
    );
    assert!(!described.contains("/dev/"), "{described}");
}

#[test]
fn a_referenced_chain_is_not_homed_again() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let first = ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain.clone()), clock.clone());
    assert!(first.is_ok());
    let homes = |chain| host_lines(chain).iter().filter(|l| l.ends_with(" home")).count();
    assert_eq!(homes(&chain), 2);
    let second = ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain.clone()), clock);
    assert!(second.is_ok());
    assert_eq!(homes(&chain), 2, "no `WR` any more: no homing");
}

#[test]
fn the_plate_moving_inverts_every_direction() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let Ok(mut stages) = ZaberStages::open(config("mock", MovingPart::Plate), ChainLine::new(chain.clone()), clock)
    else {
        panic!("open failed")
    };
    assert_eq!(stages.aim_at(0.010, -0.020), Ok(()));
    // To bring plate point (10, -20) mm under the beam, the plate goes the other way.
    assert_eq!(position(&chain, 1), Some(us(ORIGIN_MM - 10.0)));
    assert_eq!(position(&chain, 2), Some(us(ORIGIN_MM + 20.0)));
    let Ok((x_m, y_m)) = stages.position_m() else { panic!("no position") };
    assert!((x_m - 0.010).abs() < 1e-7 && (y_m + 0.020).abs() < 1e-7, "({x_m}, {y_m})");
}

#[test]
fn points_beyond_the_travel_are_refused_before_anything_moves() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let mut narrow = config("mock", MovingPart::Head);
    narrow.y.travel_max_mm = Some(80.0);
    let Ok(mut stages) = ZaberStages::open(narrow, ChainLine::new(chain.clone()), clock) else { panic!("open failed") };
    let sent = host_lines(&chain).len();
    // x: 50 + 51 mm is past the stage's 100 mm (its `limit.max`); y: 50 + 31 mm is past the configured 80 mm.
    for (x_m, y_m) in [(0.051, 0.0), (0.0, 0.031), (-0.051, 0.0)] {
        let refused = stages.check_reachable(x_m, y_m);
        assert!(matches!(refused, Err(AimError::Unreachable { .. })), "({x_m}, {y_m}): {refused:?}");
        assert_eq!(stages.aim_at(x_m, y_m), refused);
    }
    assert!(matches!(stages.check_reachable(f64::NAN, 0.0), Err(AimError::InvalidArgument { .. })));
    assert_eq!(host_lines(&chain).len(), sent, "check_reachable and a refused aim send nothing");
    assert_eq!(stages.check_reachable(0.050, 0.030), Ok(()), "the ends themselves are reachable");
}

#[test]
fn a_tripped_limit_and_a_stall_are_reported_by_name() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let Ok(mut stages) =
        ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain.clone()), clock.clone())
    else {
        panic!("open failed")
    };
    let arm = |device, code: &str| {
        let flag = WarningFlag::parse(code).unwrap_or(WarningFlag::NONE);
        chain.lock().map(|mut c| c.arm_fault(device, 1, ArmedFault { flag, fraction: 0.5 })).unwrap_or(false)
    };
    assert!(arm(2, "WL"));
    let error = stages.aim_at(0.0, 0.010);
    let Err(AimError::Device { message }) = error else { panic!("not a device error: {error:?}") };
    assert!(message.contains("y axis (device 2 axis 1): WL (unexpected limit trigger)"), "{message}");

    // Reconnecting clears the latched warning; a stall is then reported the same way.
    assert_eq!(stages.reconnect(), Ok(()));
    assert!(arm(1, "FS"));
    let Err(AimError::Device { message }) = stages.aim_at(0.020, 0.0) else { panic!("no device error") };
    assert!(message.contains("x axis (device 1 axis 1): FS (stalled and stopped)"), "{message}");
}

#[test]
fn reconnect_rehomes_after_a_power_cycle_and_returns_to_the_last_point() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let Ok(mut stages) = ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain.clone()), clock)
    else {
        panic!("open failed")
    };
    assert_eq!(stages.aim_at(0.005, 0.015), Ok(()));
    // The cable is pulled and the stages lose power.
    if let Ok(mut c) = chain.lock() {
        c.disconnect();
        c.power_cycle();
    }
    let lost = stages.aim_at(0.0, 0.0);
    assert!(lost.as_ref().is_err_and(AimError::suggests_reconnect), "{lost:?}");
    let homes_before = host_lines(&chain).iter().filter(|l| l.ends_with(" home")).count();
    assert_eq!(stages.reconnect(), Ok(()));
    assert_eq!(host_lines(&chain).iter().filter(|l| l.ends_with(" home")).count(), homes_before + 2);
    assert_eq!(position(&chain, 1), Some(us(ORIGIN_MM + 5.0)));
    assert_eq!(position(&chain, 2), Some(us(ORIGIN_MM + 15.0)));
}

#[test]
fn a_silent_chain_is_a_lost_link_and_a_bad_configuration_is_named() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let mut wrong = config("mock", MovingPart::Head);
    wrong.y.device = 7;
    let opened = ZaberStages::open(wrong, ChainLine::new(chain.clone()), clock.clone());
    assert!(matches!(opened, Err(ZaberError::NoReply { device: 7, .. })), "{opened:?}");
    let mut same = config("mock", MovingPart::Head);
    same.y.device = 1;
    let opened = ZaberStages::open(same, ChainLine::new(chain.clone()), clock.clone());
    assert!(
        matches!(&opened, Err(ZaberError::Config { key, reason }) if key == "y" && reason.contains("same axis")),
        "{opened:?}"
    );
    let mut negative = config("mock", MovingPart::Head);
    negative.x.microstep_um = -0.05;
    let opened = ZaberStages::open(negative, ChainLine::new(chain.clone()), clock.clone());
    assert!(matches!(&opened, Err(ZaberError::Config { key, .. }) if key == "x.microstep_um"), "{opened:?}");
}

#[test]
fn an_axis_that_will_not_home_is_named() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock.clone());
    let stall = ArmedFault { flag: WarningFlag::parse("FS").unwrap_or(WarningFlag::NONE), fraction: 0.3 };
    assert!(chain.lock().map(|mut c| c.arm_fault(2, 1, stall)).unwrap_or(false));
    let opened = ZaberStages::open(config("mock", MovingPart::Head), ChainLine::new(chain), clock);
    let Err(error) = opened else { panic!("opened a chain whose y axis stalls while homing") };
    let message = AimError::from(error).to_string();
    assert!(
        message.contains("y axis (device 2 axis 1): FS (stalled and stopped), WR (no reference position)"),
        "{message}"
    );
}

#[test]
fn listing_the_chain_finds_every_device() {
    let clock = Arc::new(VirtualClock::new());
    let chain = chain(SPEED_MM_PER_S, clock);
    let mut line = ChainLine::new(chain);
    let found = metaplate_aim::zaber::list_chain(&mut line, 0.2);
    let addresses: Vec<u8> = found.iter().flatten().map(|d| d.address).collect();
    assert_eq!(addresses, vec![1, 2], "{found:?}");
    assert!(found.iter().flatten().all(|d| d.device_id == "50081"));
}
