//! What a dataset records of the rig that measured it: each instrument's identity (vendor, model, serial number,
//! firmware or driver version) and the wiring with its rates. It is part of the dataset's configuration, so a resume
//! on another rig or with other cabling is refused like any changed configuration, naming what changed, unless
//! forced.

use metaplate_core::rig::Rig;
use serde_json::{Value, json};

use crate::error::RecipeError;

/// The rig as the configuration's `rig` object: `vibrometer`, `daq` and `audio` identities and `wiring`.
///
/// # Errors
/// [`RecipeError::Vibrometer`] when the vibrometer does not answer its identity query (the DAQ's and the audio
/// interface's identities were read when they were opened).
pub fn rig_config(rig: &mut Rig) -> Result<Value, RecipeError> {
    let ldv = rig.vibrometer.identify()?;
    let daq = rig.daq.identity();
    let audio = rig.audio.identity();
    let w = &rig.wiring;
    Ok(json!({
        "vibrometer": {"vendor": ldv.vendor, "model": ldv.model, "serial": ldv.serial, "firmware": ldv.firmware},
        "daq": {"vendor": daq.vendor, "model": daq.model, "serial": daq.serial, "firmware": daq.firmware},
        "audio": {"vendor": audio.vendor, "model": audio.model, "serial": audio.serial, "firmware": audio.firmware},
        "wiring": {
            "actuator_channels": w.actuator_channels,
            "loopback_channel": w.loopback_channel,
            "audio_channels": w.audio_channels,
            "audio_sample_rate_hz": w.audio_sample_rate_hz,
            "velocity_input": w.velocity_input,
            "loopback_input": w.loopback_input,
            "daq_range_v": w.daq_range_v,
            "daq_sample_rate_hz": w.daq_sample_rate_hz,
            "loopback_volts_per_full_scale": w.loopback_volts_per_full_scale,
        },
    }))
}
