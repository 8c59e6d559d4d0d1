//! Against a real Polytec controller, only on request:
//! `METAPLATE_LDV_PORT=/dev/ttyUSB0 cargo test -p metaplate-ldv --test tests real_controller -- --ignored`
//! (optionally `METAPLATE_LDV_DECODER=VD-09`). It reads the identity, the decoder's ranges and the signal level,
//! and sets the most sensitive range and reads it back; it does not focus.

use metaplate_core::vibrometer::Vibrometer;
use metaplate_ldv::{DecoderChoice, PolytecConfig, PolytecDriver, PortSelector, RetryPolicy, SerialPortLine};

#[test]
#[ignore = "needs a real Polytec controller: set METAPLATE_LDV_PORT and run with --ignored"]
fn real_controller_identifies_and_takes_a_range() {
    // Run on purpose without a port: fail loudly rather than pass without testing anything.
    let port = std::env::var("METAPLATE_LDV_PORT").expect("set METAPLATE_LDV_PORT=/dev/ttyUSB0 (or a by-id path)");
    let decoder = std::env::var("METAPLATE_LDV_DECODER").map_or(DecoderChoice::First, DecoderChoice::Name);
    let line = SerialPortLine::open(PortSelector::Path(port.into())).unwrap();
    let config = PolytecConfig { decoder, ..PolytecConfig::default() };
    let mut ldv = PolytecDriver::new(line, RetryPolicy::default(), config).unwrap();
    let id = ldv.identify().unwrap();
    assert_eq!(id.vendor, "Polytec");
    let decoder = ldv.decoder().unwrap();
    assert!(!decoder.ranges.is_empty());
    let smallest = decoder.ranges[0].m_s_per_v() * metaplate_ldv::OUTPUT_FULL_SCALE_V;
    let scale = ldv.set_velocity_range(smallest).unwrap();
    assert!((scale.full_scale_m_s - smallest).abs() <= 1e-12 * smallest);
    let level = ldv.signal_level().unwrap();
    assert!((0.0..=1.0).contains(&level));
    ldv.reconnect().unwrap();
    eprintln!("{id:?}, {decoder:?}, level {level}");
}
