//! The stand-in rig's aim: two Zaber linear stages carrying the vibrometer's head (X: device 1, Y: device 2, one
//! axis each), served on a pseudo-terminal, moving in real time. A thread puts the lab's beam where the stages are.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use metaplate_core::clock::RealClock;
use metaplate_core::scene::FaultKind;
use metaplate_mock_ldv::PtyServer;
use metaplate_mock_zaber::{ArmedFault, AxisSpec, ChainSpec, DeviceSpec, MockChain};
use metaplate_zaber_protocol::WarningFlag;

use super::IDLE_POLL;
use crate::{LabError, MockLab};

/// Microstep of the stages, µm: what Zaber lists for its X-LSM and X-LRQ stages at resolution 64.
const MICROSTEP_UM: f64 = 0.047_625;
/// Stage speed, mm/s.
const SPEED_MM_PER_S: f64 = 250.0;
/// Travel beyond the farthest point on each side, mm.
const MARGIN_MM: f64 = 10.0;

/// One axis: the stage position (mm from home) that puts the beam on the plate's origin, and its travel, mm.
#[derive(Debug, Clone, Copy)]
struct Axis {
    origin_mm: f64,
    travel_mm: f64,
}

impl Axis {
    /// An axis reaching every coordinate in `coords_m` with [`MARGIN_MM`] to spare.
    fn spanning(coords_m: impl Iterator<Item = f64> + Clone) -> Axis {
        let lo_mm = coords_m.clone().fold(0.0_f64, f64::min) * 1e3;
        let hi_mm = coords_m.fold(0.0_f64, f64::max) * 1e3;
        Axis { origin_mm: MARGIN_MM - lo_mm, travel_mm: hi_mm - lo_mm + 2.0 * MARGIN_MM }
    }

    fn spec(self) -> AxisSpec {
        let limit_max_us = (self.travel_mm * 1e3 / MICROSTEP_UM).round() as i64;
        AxisSpec {
            limit_min_us: 0,
            limit_max_us,
            resolution: 64,
            speed_us_per_s: SPEED_MM_PER_S * 1e3 / MICROSTEP_UM,
            power_up_pos_us: limit_max_us / 2,
        }
    }

    /// The plate coordinate under the beam at stage position `us`, m.
    fn plate_m(self, us: i64) -> f64 {
        (us as f64 * MICROSTEP_UM * 1e-3 - self.origin_mm) * 1e-3
    }
}

/// Serves the stages: the pseudo-terminal, the thread that moves the beam, and the hardware file's `[aim]`.
///
/// # Errors
/// [`LabError::Pty`] when the pseudo-terminal cannot be opened; [`LabError::Serve`] when the thread cannot start.
pub(super) fn serve(lab: &MockLab, stop: Arc<AtomicBool>) -> Result<(PtyServer, JoinHandle<()>, String), LabError> {
    let scene = lab.scene();
    let positions: Vec<(f64, f64)> =
        (0..scene.grid.len() + scene.actuators.len()).map(|p| crate::point_position_m(scene, p)).collect();
    let x = Axis::spanning(positions.iter().map(|p| p.0));
    let y = Axis::spanning(positions.iter().map(|p| p.1));
    let device = |address: u8, axis: Axis| DeviceSpec {
        address,
        device_id: 50_081,
        serial: 12_340 + u32::from(address),
        axes: vec![axis.spec()],
    };
    let spec = ChainSpec { devices: vec![device(1, x), device(2, y)], reply_checksums: false };
    let mut chain = MockChain::new(spec, Arc::new(RealClock::new()));
    if lab.windows.of_kind(FaultKind::StageStall).next().is_some() {
        // Stalled a third of the way: the driver sees the axis stop short with `FS` latched.
        let stall = ArmedFault { flag: WarningFlag::parse("FS").unwrap_or(WarningFlag::NONE), fraction: 0.3 };
        chain.arm_fault(2, 1, stall);
    }
    let chain = Arc::new(Mutex::new(chain));
    let server = PtyServer::spawn(Arc::clone(&chain))?;
    let ldv = Arc::clone(&lab.ldv);
    let bridge = std::thread::Builder::new()
        .name("stand-in-stages".into())
        .spawn(move || {
            let mut last = None;
            while !stop.load(Ordering::Acquire) {
                let at = chain.lock().ok().and_then(|mut c| Some((c.position_us(1, 1)?, c.position_us(2, 1)?)));
                if at.is_some() && at != last {
                    if let (Some((xu, yu)), Ok(mut device)) = (at, ldv.lock()) {
                        device.controller_mut().set_beam(x.plate_m(xu), y.plate_m(yu));
                    }
                    last = at;
                }
                std::thread::sleep(IDLE_POLL);
            }
        })
        .map_err(|e| LabError::Serve { what: format!("starting the stages' thread: {e}") })?;
    let section = format!(
        "# Two Zaber stages carrying the head, on a pseudo-terminal.\n[aim]\nbackend = \"zaber\"\nport = {:?}\n\
         moves = \"head\"\n\n[aim.x]\ndevice = 1\nmicrostep_um = {MICROSTEP_UM}\norigin_mm = {:?}\n\n[aim.y]\n\
         device = 2\nmicrostep_um = {MICROSTEP_UM}\norigin_mm = {:?}\n",
        server.path().display().to_string(),
        x.origin_mm,
        y.origin_mm
    );
    Ok((server, bridge, section))
}
