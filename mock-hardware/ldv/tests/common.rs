//! What the mock tests share: a unit on a device, on a clock.

use std::sync::{Arc, Mutex};

use metaplate_core::clock::VirtualClock;
use metaplate_core::scene::LdvSpec;
use metaplate_mock_ldv::{FaultSchedule, MockController, MockDevice, UnitSpec};

pub const SEED: u64 = 11;

pub fn spec() -> LdvSpec {
    metaplate_mock_ldv::quiet_spec()
}

pub fn device(unit: UnitSpec, faults: FaultSchedule, clock: Arc<VirtualClock>) -> Arc<Mutex<MockDevice>> {
    let mut controller = MockController::new(unit, &spec(), SEED);
    controller.set_beam(0.03, -0.02);
    Arc::new(Mutex::new(MockDevice::new(controller, faults).with_clock(clock)))
}

pub fn host_log(device: &Mutex<MockDevice>) -> String {
    String::from_utf8_lossy(device.lock().unwrap().host_log()).into_owned()
}
