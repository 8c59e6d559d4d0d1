//! What a dataset records of the rig that measured it: each instrument's identity (vendor, model, serial number,
//! firmware or driver version) and the wiring with its rates. It is part of the dataset's configuration, so a resume
//! on another rig or with other cabling is refused like any changed configuration, naming what changed, unless
//! forced.

use metaplate_core::rig::{Rig, Wiring};
use serde_json::{Map, Value, json};

use crate::error::RecipeError;

/// The rig as the configuration's `rig` object: `vibrometer`, `daq` and `audio` identities, what aims the beam
/// (`aim`, in words: [`metaplate_core::aim::Aim::describe`]) and `wiring`.
///
/// # Errors
/// [`RecipeError::Vibrometer`] when the vibrometer does not answer its identity query (the DAQ's and the audio
/// interface's identities were read when they were opened).
pub fn rig_config(rig: &mut Rig) -> Result<Value, RecipeError> {
    let ldv = rig.vibrometer.identify()?;
    let daq = rig.daq.identity();
    let audio = rig.audio.identity();
    Ok(json!({
        "vibrometer": {"vendor": ldv.vendor, "model": ldv.model, "serial": ldv.serial, "firmware": ldv.firmware},
        "daq": {"vendor": daq.vendor, "model": daq.model, "serial": daq.serial, "firmware": daq.firmware},
        "audio": {"vendor": audio.vendor, "model": audio.model, "serial": audio.serial, "firmware": audio.firmware},
        "aim": rig.aim.describe(),
        "wiring": wiring_json(&rig.wiring),
    }))
}

/// The wiring as the configuration records it.
fn wiring_json(w: &Wiring) -> Value {
    json!({
        "actuator_channels": w.actuator_channels,
        "loopback_channel": w.loopback_channel,
        "audio_channels": w.audio_channels,
        "audio_sample_rate_hz": w.audio_sample_rate_hz,
        "velocity_input": w.velocity_input,
        "loopback_input": w.loopback_input,
        "daq_range_v": w.daq_range_v,
        "daq_sample_rate_hz": w.daq_sample_rate_hz,
        "loopback_volts_per_full_scale": w.loopback_volts_per_full_scale,
    })
}

/// The wiring a dataset's configuration records (its `rig.wiring`, as [`rig_config`] writes it): how the rig that
/// measured it was cabled, for work that renders drives for that rig without opening it.
///
/// # Errors
/// [`RecipeError::Config`] naming the key that is missing or out of range (a dataset written before the rig was
/// recorded has none).
pub fn recorded_wiring(config: &Map<String, Value>) -> Result<Wiring, RecipeError> {
    let w = config.get("rig").and_then(|r| r.get("wiring")).ok_or_else(|| {
        RecipeError::Config("the dataset records no rig wiring (`rig.wiring`): it predates the rig record".into())
    })?;
    let missing = |key: &str| RecipeError::Config(format!("the recorded wiring has no valid `rig.wiring.{key}`"));
    let number = |key: &'static str| w.get(key).and_then(Value::as_f64).ok_or_else(|| missing(key));
    let uint = |key: &'static str| w.get(key).and_then(Value::as_u64).ok_or_else(|| missing(key));
    let small = |key: &'static str, max: u64| uint(key).and_then(|v| if v <= max { Ok(v) } else { Err(missing(key)) });
    let actuator_channels = w
        .get("actuator_channels")
        .and_then(Value::as_array)
        .and_then(|a| a.iter().map(|c| c.as_u64().and_then(|c| u32::try_from(c).ok())).collect::<Option<Vec<u32>>>())
        .ok_or_else(|| missing("actuator_channels"))?;
    let wiring = Wiring {
        actuator_channels,
        loopback_channel: small("loopback_channel", u64::from(u32::MAX))? as u32,
        audio_channels: small("audio_channels", u64::from(u32::MAX))? as u32,
        audio_sample_rate_hz: number("audio_sample_rate_hz")?,
        velocity_input: small("velocity_input", u64::from(u8::MAX))? as u8,
        loopback_input: small("loopback_input", u64::from(u8::MAX))? as u8,
        daq_range_v: number("daq_range_v")?,
        daq_sample_rate_hz: number("daq_sample_rate_hz")?,
        loopback_volts_per_full_scale: number("loopback_volts_per_full_scale")?,
    };
    wiring.validate().map_err(|reason| RecipeError::Config(format!("the recorded wiring: {reason}")))?;
    Ok(wiring)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recorded_wiring_reads_back_and_a_missing_or_bad_key_is_named() {
        let wiring = Wiring {
            actuator_channels: vec![3, 1, 2, 0],
            loopback_channel: 8,
            audio_channels: 10,
            audio_sample_rate_hz: 48_000.0,
            velocity_input: 0,
            loopback_input: 1,
            daq_range_v: 10.0,
            daq_sample_rate_hz: 24_000.0,
            loopback_volts_per_full_scale: 1.0,
        };
        let config = |w: Value| json!({"rig": {"wiring": w}}).as_object().cloned().unwrap_or_default();
        assert_eq!(recorded_wiring(&config(wiring_json(&wiring))).ok(), Some(wiring.clone()));
        let mut bad = wiring_json(&wiring);
        bad["loopback_input"] = json!(300);
        let message = recorded_wiring(&config(bad)).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.contains("rig.wiring.loopback_input"), "{message}");
        let message = recorded_wiring(&Map::new()).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(message.contains("predates the rig record"), "{message}");
    }
}
