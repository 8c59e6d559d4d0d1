//! Zaber stages on a real serial port, run on purpose with
//! `METAPLATE_ZABER_PORT=/dev/ttyUSB0 cargo test -p metaplate-mock-zaber --test tests real_stages -- --ignored
//! --nocapture` (optionally `METAPLATE_ZABER_MICROSTEP_UM=0.047625`, the stages' microstep size at resolution 64).
//! x is device 1 axis 1 and y device 2 axis 1; it opens (homing an axis without its reference), moves the head to
//! 10 mm and then 12 mm from home on both axes and reads the positions back, then reconnects: keep the travel clear.

use metaplate_aim::zaber::{MovingPart, open_serial};
use metaplate_core::aim::Aim;

use crate::common::config;

#[test]
#[ignore = "needs Zaber stages: set METAPLATE_ZABER_PORT and run with --ignored"]
fn real_stages_home_move_and_reconnect() {
    // Run on purpose without a port: fail loudly rather than pass without testing anything.
    let port = std::env::var("METAPLATE_ZABER_PORT").expect("set METAPLATE_ZABER_PORT=/dev/ttyUSB0 (or a by-id path)");
    let mut config = config(&port, MovingPart::Head);
    if let Ok(microstep) = std::env::var("METAPLATE_ZABER_MICROSTEP_UM") {
        let microstep_um: f64 = microstep.parse().expect("METAPLATE_ZABER_MICROSTEP_UM is a number of µm");
        config.x.microstep_um = microstep_um;
        config.y.microstep_um = microstep_um;
    }
    // The plate's origin 10 mm from home: the moves stay near home on any stage.
    config.x.origin_mm = 10.0;
    config.y.origin_mm = 10.0;
    let mut stages = open_serial(config).unwrap();
    eprintln!("{}", stages.describe());
    for (x_m, y_m) in [(0.0, 0.0), (0.002, 0.002)] {
        stages.aim_at(x_m, y_m).unwrap();
        let (read_x_m, read_y_m) = stages.position_m().unwrap();
        // Within a few microsteps (a closed-loop stage settles to within them).
        assert!((read_x_m - x_m).abs() < 1e-6 && (read_y_m - y_m).abs() < 1e-6, "({read_x_m}, {read_y_m})");
    }
    stages.reconnect().unwrap();
}
