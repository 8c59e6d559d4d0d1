//! A chain, the driver's configuration for it, and the conversions the tests check positions with.

use std::sync::{Arc, Mutex};

use metaplate_aim::zaber::{MovingPart, StageAxisConfig, ZaberConfig};
use metaplate_core::clock::Clock;
use metaplate_ldv::PortSelector;
use metaplate_mock_zaber::{ChainSpec, MockChain};

/// The X-LSM stages' microstep at resolution 64, µm (what [`metaplate_mock_zaber::AxisSpec::lsm100`] models).
pub const MICROSTEP_UM: f64 = 0.047_625;

/// Where the plate's origin is on both stages, mm from home.
pub const ORIGIN_MM: f64 = 50.0;

/// The stage position, microsteps, `mm` from home.
pub fn us(mm: f64) -> i64 {
    (mm * 1e3 / MICROSTEP_UM).round() as i64
}

/// A chain of two 100 mm stages moving at `speed_mm_per_s`, timed by `clock`.
pub fn chain(speed_mm_per_s: f64, clock: Arc<dyn Clock>) -> Arc<Mutex<MockChain>> {
    Arc::new(Mutex::new(MockChain::new(ChainSpec::xy_lsm100(speed_mm_per_s), clock)))
}

/// x on device 1, y on device 2, origin at 50 mm on both.
pub fn config(port: &str, moving: MovingPart) -> ZaberConfig {
    let axis = |device| StageAxisConfig {
        device,
        axis: 1,
        microstep_um: MICROSTEP_UM,
        origin_mm: ORIGIN_MM,
        travel_min_mm: None,
        travel_max_mm: None,
    };
    ZaberConfig::new(PortSelector::Path(port.into()), moving, axis(1), axis(2))
}

/// The host's commands so far, one per line.
pub fn host_lines(chain: &Mutex<MockChain>) -> Vec<String> {
    let log = chain.lock().map(|c| c.host_log().to_vec()).unwrap_or_default();
    String::from_utf8_lossy(&log).lines().map(str::to_owned).collect()
}
