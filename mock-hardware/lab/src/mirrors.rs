//! The lab's galvanometer mirrors: two analog outputs whose voltages steer the beam, through a geometry the host
//! does not know and must learn by teaching.
//!
//! Where the beam lands for voltages `v = (x_v, y_v)` ([`MirrorGeometry::landing_m`]):
//! 1. linear: `l = R(rotation) * diag(scale, scale * aspect) * v` (the mirrors' deflection per volt seen on the
//!    plate, their axes turned against the plate's);
//! 2. keystone: `l / (1 + keystone . v)` (the head is not square to the plate: a projective distortion);
//! 3. pincushion: `l * (1 + pincushion * |l|^2)` (the two-mirror geometry's small non-linearity, cubic, a few
//!    tenths of a millimetre at the plate's edge, as two mirrors without a flat-field lens give: the part no projective fit can take);
//! 4. plus the offset of the optical centre from the plate's origin.
//!
//! Each parameter is drawn from the seed in a range typical of a small-mirror scanner a metre from a plate
//! ([`MirrorGeometry::seeded`]). The lab knows where the beam lands ([`MockMirrors::beam_m`], for a simulated user
//! or a test); the host only writes voltages. Attached to a lab ([`crate::MockLab::mirrors`]) the beam is the
//! lab's vibrometer's: it measures where the mirrors point.

use std::sync::{Arc, Mutex};

use metaplate_core::aim::{AimError, MirrorOutputs};
use metaplate_core::rng::SplitMix64;
use metaplate_mock_ldv::MockDevice;

/// The outputs' range, V: +/- 10 V, as the common galvo drivers take (Thorlabs GVS series).
pub const MIRRORS_LIMIT_V: f64 = 10.0;

/// Stream constant of the mirrors' geometry draws (apart from every other draw of the seed).
const GEOMETRY_STREAM: u64 = 0x6761_6c76_6f00_0001;

/// Where the beam lands for given voltages; see the module documentation for the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorGeometry {
    /// The optical centre on the plate (where 0 V, 0 V lands), m.
    pub offset_m: (f64, f64),
    /// The X mirror's deflection on the plate, m per V.
    pub scale_m_per_v: f64,
    /// The Y mirror's deflection over the X mirror's (the two are not matched).
    pub aspect: f64,
    /// The mirrors' axes against the plate's, rad.
    pub rotation_rad: f64,
    /// The keystone, per V on each axis.
    pub keystone_per_v: (f64, f64),
    /// The cubic non-linearity, per m².
    pub pincushion_per_m2: f64,
}

impl MirrorGeometry {
    /// A geometry drawn from `seed`: scale 18 to 22 mm/V, aspect 0.97 to 1.03, rotation +/- 3 degrees, offset
    /// +/- 8 mm on each axis, keystone +/- 0.4 % per V, pincushion 0.1 to 0.2 per m² (0.2 to 0.45 mm at
    /// 0.13 m from the centre).
    pub fn seeded(seed: u64) -> MirrorGeometry {
        let mut rng = SplitMix64::new(seed, GEOMETRY_STREAM);
        let mut within = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        MirrorGeometry {
            scale_m_per_v: within(0.018, 0.022),
            aspect: within(0.97, 1.03),
            rotation_rad: within(-3.0, 3.0).to_radians(),
            offset_m: (within(-0.008, 0.008), within(-0.008, 0.008)),
            keystone_per_v: (within(-0.004, 0.004), within(-0.004, 0.004)),
            pincushion_per_m2: within(0.1, 0.2),
        }
    }

    /// Where the beam lands on the plate for (`x_v`, `y_v`), m.
    pub fn landing_m(&self, x_v: f64, y_v: f64) -> (f64, f64) {
        let (sx, sy) = (self.scale_m_per_v * x_v, self.scale_m_per_v * self.aspect * y_v);
        let (sin, cos) = self.rotation_rad.sin_cos();
        let (lx, ly) = (cos * sx - sin * sy, sin * sx + cos * sy);
        let w = 1.0 + self.keystone_per_v.0 * x_v + self.keystone_per_v.1 * y_v;
        let (kx, ky) = (lx / w, ly / w);
        let radial = 1.0 + self.pincushion_per_m2 * (kx * kx + ky * ky);
        (self.offset_m.0 + kx * radial, self.offset_m.1 + ky * radial)
    }
}

#[derive(Debug)]
struct State {
    geometry: MirrorGeometry,
    volts: Option<(f64, f64)>,
    disconnected: bool,
    ldv: Option<Arc<Mutex<MockDevice>>>,
}

/// The mock mirrors' outputs. Clones share one pair of mirrors (give one to the aimer, keep one to see where the
/// beam lands).
#[derive(Debug, Clone)]
pub struct MockMirrors {
    state: Arc<Mutex<State>>,
}

impl MockMirrors {
    /// Mirrors of `geometry`, on their own (no vibrometer: [`MockMirrors::beam_m`] says where the beam lands).
    pub fn new(geometry: MirrorGeometry) -> MockMirrors {
        MockMirrors { state: Arc::new(Mutex::new(State { geometry, volts: None, disconnected: false, ldv: None })) }
    }

    /// Mirrors that put the beam of `ldv` (the lab's vibrometer) where they point.
    pub(crate) fn on_ldv(geometry: MirrorGeometry, ldv: Arc<Mutex<MockDevice>>) -> MockMirrors {
        let mirrors = MockMirrors::new(geometry);
        if let Ok(mut state) = mirrors.state.lock() {
            state.ldv = Some(ldv);
        }
        mirrors
    }

    fn lock(&self) -> Result<std::sync::MutexGuard<'_, State>, AimError> {
        self.state.lock().map_err(|_| AimError::Device { message: "the mock mirrors' lock is poisoned".into() })
    }

    /// Where the beam lands on the plate, m; `None` before the first write (or with a poisoned lock).
    pub fn beam_m(&self) -> Option<(f64, f64)> {
        let state = self.lock().ok()?;
        state.volts.map(|(x_v, y_v)| state.geometry.landing_m(x_v, y_v))
    }

    /// The voltages the outputs hold, V; `None` before the first write.
    pub fn volts(&self) -> Option<(f64, f64)> {
        self.lock().ok()?.volts
    }

    /// The mirrors' geometry (the truth a test compares a fit with).
    pub fn geometry(&self) -> Option<MirrorGeometry> {
        Some(self.lock().ok()?.geometry)
    }

    /// Unplugs the output device: writes fail with `Disconnected` until [`MirrorOutputs::reconnect`]. The mirrors
    /// keep their last voltages (as real outputs hold theirs).
    pub fn disconnect(&self) {
        if let Ok(mut state) = self.state.lock() {
            state.disconnected = true;
        }
    }
}

impl MirrorOutputs for MockMirrors {
    fn set_volts(&mut self, x_v: f64, y_v: f64) -> Result<(), AimError> {
        let mut state = self.lock()?;
        let in_range = |v: f64| v.is_finite() && v.abs() <= MIRRORS_LIMIT_V;
        if !in_range(x_v) || !in_range(y_v) {
            return Err(AimError::InvalidArgument {
                detail: format!("({x_v} V, {y_v} V) is outside the outputs' +/- {MIRRORS_LIMIT_V} V"),
            });
        }
        if state.disconnected {
            return Err(AimError::Disconnected { reason: "the mock mirrors' output device is unplugged".into() });
        }
        state.volts = Some((x_v, y_v));
        let (x_m, y_m) = state.geometry.landing_m(x_v, y_v);
        if let Some(ldv) = &state.ldv {
            let mut ldv =
                ldv.lock().map_err(|_| AimError::Device { message: "the lab's LDV lock is poisoned".into() })?;
            ldv.controller_mut().set_beam(x_m, y_m);
        }
        Ok(())
    }

    fn limit_v(&self) -> f64 {
        MIRRORS_LIMIT_V
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        self.lock()?.disconnected = false;
        Ok(())
    }

    fn describe(&self) -> String {
        format!("the mock lab's galvo mirrors (+/- {MIRRORS_LIMIT_V} V)")
    }
}
