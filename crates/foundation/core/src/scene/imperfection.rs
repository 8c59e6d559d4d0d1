//! The imperfections a simulated lab models, each of which a scene can switch off: the one list an error budget
//! and its tests share.

use super::Scene;

/// One imperfection of the simulated lab, and how a scene switches it off ([`Scene::without`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Imperfection {
    /// The vibrometer's velocity noise floor: `ldv.noise_rms_m_s = 0`.
    LdvNoise,
    /// Speckle: the returned light's level varying from spot to spot (it scales the noise and what `SIG?` reads):
    /// `ldv.speckle_spread = 0`, `ldv.speckle_mean_level = 1`.
    Speckle,
    /// Random signal dropouts: `ldv.dropout_probability = 0`.
    Dropouts,
    /// The DAQ's quantisation to `daq.bits`: `daq.bits = 0` (an ideal converter).
    Quantisation,
    /// Clipping at the vibrometer's range and the DAQ's input range: `daq.clipping = false`.
    Clipping,
    /// The audio interface's and the DAQ's clock offsets from nominal: both `clock_offset_ppm = 0`.
    ClockDrift,
    /// The audio interface's output latency: `audio.latency_s = 0`.
    Latency,
    /// The voice coils' cubic nonlinearity: every actuator's `nonlinearity = 0`.
    Nonlinearity,
    /// The voice coils' unit-to-unit gain spread: every actuator's `spread_db = 0`.
    ActuatorSpread,
    /// The scanner's beam positioning error: `ldv.aim_error_rms_m = 0`.
    AimError,
    /// The scene's scheduled faults (timeouts, stalls, dropout windows, underruns, disconnects): none.
    Faults,
}

/// Every imperfection, in the order of [`Imperfection::all`].
const ALL: [Imperfection; 11] = [
    Imperfection::LdvNoise,
    Imperfection::Speckle,
    Imperfection::Dropouts,
    Imperfection::Quantisation,
    Imperfection::Clipping,
    Imperfection::ClockDrift,
    Imperfection::Latency,
    Imperfection::Nonlinearity,
    Imperfection::ActuatorSpread,
    Imperfection::AimError,
    Imperfection::Faults,
];

impl Imperfection {
    /// Every imperfection the simulated lab models.
    pub fn all() -> &'static [Imperfection] {
        &ALL
    }

    /// Its name in tables and on the command line (kebab case: `ldv-noise`, `clock-drift`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::LdvNoise => "ldv-noise",
            Self::Speckle => "speckle",
            Self::Dropouts => "dropouts",
            Self::Quantisation => "quantisation",
            Self::Clipping => "clipping",
            Self::ClockDrift => "clock-drift",
            Self::Latency => "latency",
            Self::Nonlinearity => "nonlinearity",
            Self::ActuatorSpread => "actuator-spread",
            Self::AimError => "aim-error",
            Self::Faults => "faults",
        }
    }

    /// The imperfection of that [`Imperfection::name`], if any.
    pub fn by_name(name: &str) -> Option<Imperfection> {
        ALL.iter().copied().find(|i| i.name() == name)
    }

    /// Whether `scene` has this imperfection at all (a term it lacks adds nothing to a budget).
    pub fn is_present(self, scene: &Scene) -> bool {
        scene.without(&[self]) != *scene
    }

    /// Switches this imperfection off in `scene`.
    fn switch_off(self, scene: &mut Scene) {
        match self {
            Self::LdvNoise => scene.ldv.noise_rms_m_s = 0.0,
            Self::Speckle => {
                scene.ldv.speckle_spread = 0.0;
                scene.ldv.speckle_mean_level = 1.0;
            }
            Self::Dropouts => scene.ldv.dropout_probability = 0.0,
            Self::Quantisation => scene.daq.bits = 0,
            Self::Clipping => scene.daq.clipping = false,
            Self::ClockDrift => {
                scene.audio.clock_offset_ppm = 0.0;
                scene.daq.clock_offset_ppm = 0.0;
            }
            Self::Latency => scene.audio.latency_s = 0.0,
            Self::Nonlinearity => scene.actuators.iter_mut().for_each(|a| a.voice_coil.nonlinearity = 0.0),
            Self::ActuatorSpread => scene.actuators.iter_mut().for_each(|a| a.voice_coil.spread_db = 0.0),
            Self::AimError => scene.ldv.aim_error_rms_m = 0.0,
            Self::Faults => scene.faults.clear(),
        }
    }
}

impl std::fmt::Display for Imperfection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Scene {
    /// This scene with the imperfections `off` switched off (see [`Imperfection`] for what each sets), the rest as
    /// they are. The plate is untouched, so the variant shares the scene's [`Scene::physics_hash`] (and its cached
    /// Green's functions). The result is valid whenever `self` is.
    pub fn without(&self, off: &[Imperfection]) -> Scene {
        let mut scene = self.clone();
        for imperfection in off {
            imperfection.switch_off(&mut scene);
        }
        scene
    }

    /// This scene with only the imperfections `on` left as they are and every other one switched off:
    /// `with_only(&[])` is the ideal lab, `with_only(Imperfection::all())` the scene itself.
    pub fn with_only(&self, on: &[Imperfection]) -> Scene {
        let off: Vec<Imperfection> = Imperfection::all().iter().copied().filter(|i| !on.contains(i)).collect();
        self.without(&off)
    }
}
