//! What a mock chain holds: its devices, their axes, and how each axis moves.

/// One axis of a mock device: travel limits, resolution and speed, in the device's units (microsteps).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSpec {
    /// `limit.min`, microsteps (0 on Zaber's linear stages: the home sensor's side).
    pub limit_min_us: i64,
    /// `limit.max`, microsteps: the travel.
    pub limit_max_us: i64,
    /// `resolution`: microsteps per full step (64 by default on Zaber's stepper products).
    pub resolution: u32,
    /// How fast the axis moves, microsteps per second (constant: the mock does not model acceleration).
    pub speed_us_per_s: f64,
    /// Where the axis is at power-up, microsteps: arbitrary until homed (`WR`).
    pub power_up_pos_us: i64,
}

impl AxisSpec {
    /// A linear stage with 100 mm of travel at 0.047625 µm per microstep (the "Microstep Size (Default
    /// Resolution)" Zaber lists for its X-LSM stages, at resolution 64), so `limit.max` = 2,099,738 microsteps;
    /// moving at `speed_mm_per_s`.
    pub fn lsm100(speed_mm_per_s: f64) -> Self {
        Self {
            limit_min_us: 0,
            limit_max_us: 2_099_738,
            resolution: 64,
            speed_us_per_s: speed_mm_per_s * 1e3 / 0.047_625,
            power_up_pos_us: 1_049_869,
        }
    }
}

/// One device of the chain (an integrated stage, or a controller with several axes).
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceSpec {
    /// The device's address on the chain (1 to 99).
    pub address: u8,
    /// `deviceid`, Zaber's number for the product (any number in the mock).
    pub device_id: u32,
    /// `system.serial`.
    pub serial: u32,
    /// Its axes, numbered from 1.
    pub axes: Vec<AxisSpec>,
}

/// The chain on one serial port.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainSpec {
    /// Devices, in chain order.
    pub devices: Vec<DeviceSpec>,
    /// Whether replies carry checksums (`comm.checksum 1`; off by default on real devices).
    pub reply_checksums: bool,
}

impl ChainSpec {
    /// Two such stages ([`AxisSpec::lsm100`]) at addresses 1 and 2 (X and Y), each one axis, moving at `speed_mm_per_s`.
    pub fn xy_lsm100(speed_mm_per_s: f64) -> Self {
        let device = |address: u8| DeviceSpec {
            address,
            device_id: 50_081,
            serial: 12_340 + u32::from(address),
            axes: vec![AxisSpec::lsm100(speed_mm_per_s)],
        };
        Self { devices: vec![device(1), device(2)], reply_checksums: false }
    }
}
