//! Against a real LDV controller, only on request:
//! `METAPLATE_LDV_PORT=/dev/ttyUSB0 cargo test -p metaplate-ldv --test real_controller -- --ignored`.
//! It reads the identity and the calibration, and sets the power-on velocity range and tracking filter; it does not
//! switch the laser or move the beam.

use std::sync::Arc;

use metaplate_core::clock::RealClock;
use metaplate_core::vibrometer::{Tracking, Vibrometer};
use metaplate_ldv::{LdvDriver, PortSelector, RetryPolicy, SerialPortLine};

#[test]
#[ignore = "needs a real LDV controller: set METAPLATE_LDV_PORT and run with --ignored"]
fn real_controller_identifies_and_takes_settings() {
    // Run on purpose without a port: fail loudly rather than pass without testing anything.
    let port = std::env::var("METAPLATE_LDV_PORT").expect("set METAPLATE_LDV_PORT=/dev/ttyUSB0 (or a by-id path)");
    let line = SerialPortLine::open(PortSelector::Path(port.into())).unwrap();
    let mut ldv = LdvDriver::new(line, Arc::new(RealClock::new()), RetryPolicy::default()).unwrap();
    let id = ldv.identify().unwrap();
    assert!(!id.serial.is_empty());
    // The power-on defaults: 25 mm/s/V and no tracking.
    let scale = ldv.set_velocity_range(0.25).unwrap();
    assert_eq!(scale.full_scale_m_s, 25.0 * 1e-3 * 10.0);
    ldv.set_tracking(Tracking::Off).unwrap();
    ldv.reconnect().unwrap();
    eprintln!("{id:?}");
}
