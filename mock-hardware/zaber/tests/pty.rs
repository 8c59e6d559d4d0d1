//! The stage driver on the real serial port (`serialport`, the code path a rig runs), opened on a
//! pseudo-terminal the mock chain answers on: real time, so the stages move fast here.

use std::sync::Arc;
use std::time::Instant;

use metaplate_aim::zaber::{MovingPart, open_serial};
use metaplate_core::aim::{Aim, AimError};
use metaplate_core::clock::RealClock;
use metaplate_mock_zaber::PtyServer;

use crate::common::{ORIGIN_MM, chain, config, us};

/// Fast enough that homing from 50 mm takes 0.25 s.
const SPEED_MM_PER_S: f64 = 200.0;

#[test]
fn the_real_port_opens_homes_moves_and_reconnects() {
    let chain = chain(SPEED_MM_PER_S, Arc::new(RealClock::new()));
    let server = PtyServer::spawn(chain.clone());
    let Ok(server) = server else { panic!("no pseudo-terminal: {server:?}") };
    let port = server.path().to_string_lossy().into_owned();

    let opened = open_serial(config(&port, MovingPart::Head));
    let Ok(mut stages) = opened else { panic!("open failed: {opened:?}") };
    let position = |device| chain.lock().ok().and_then(|mut c| c.position_us(device, 1));
    assert_eq!((position(1), position(2)), (Some(0), Some(0)), "homed on open");

    // From home to plate (20 mm, 0): 70 mm at 200 mm/s, 0.35 s, which the aimer waits out.
    let start = Instant::now();
    assert_eq!(stages.aim_at(0.020, 0.0), Ok(()));
    let waited_s = start.elapsed().as_secs_f64();
    assert!((0.35..5.0).contains(&waited_s), "waited {waited_s} s");
    assert_eq!(position(1), Some(us(ORIGIN_MM + 20.0)));
    assert_eq!(position(2), Some(us(ORIGIN_MM)));

    assert!(matches!(stages.check_reachable(0.0, 0.060), Err(AimError::Unreachable { .. })));

    // A power cycle: reconnect reopens the port, homes again and returns to the last point.
    if let Ok(mut c) = chain.lock() {
        c.power_cycle();
    }
    assert_eq!(stages.reconnect(), Ok(()));
    assert_eq!(position(1), Some(us(ORIGIN_MM + 20.0)));
    assert_eq!(position(2), Some(us(ORIGIN_MM)));
}
