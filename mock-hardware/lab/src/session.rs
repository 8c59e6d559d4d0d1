//! A playback-and-recording session through a [`Rig`]'s capabilities, for the lab's tests and benchmark: the rig's
//! own [`Rig::play_and_record`] (the one the recipes' engine uses, without its retries and recovery), with the
//! buffers built from one actuator's drive and the loopback.

pub use metaplate_core::rig::Recording;
use metaplate_core::rig::Rig;

/// Configures the audio interface (every wired channel at the wiring's rate) and the DAQ (velocity and loopback
/// at the wiring's range and rate, `block_len_samples` per block), as [`metaplate_core::rig::Wiring`] says.
///
/// # Errors
/// The drivers' errors, as text.
pub fn configure(rig: &mut Rig, block_len_samples: u32) -> Result<(), String> {
    let (audio, daq) = (rig.wiring.audio_config(), rig.wiring.daq_config(block_len_samples));
    rig.audio.configure(&audio).map_err(|e| e.to_string())?;
    rig.daq.configure(&daq).map_err(|e| e.to_string())
}

/// Plays `drive` on `actuator` with `loopback` on the loopback channel (both at the audio rate, same length) and
/// records `record_samples` DAQ samples per channel, starting the DAQ first.
///
/// # Errors
/// The drivers' errors, as text; an unknown actuator or a loopback of another length than the drive.
pub fn play_and_record(
    rig: &mut Rig,
    actuator: usize,
    drive: &[f64],
    loopback: &[f64],
    record_samples: usize,
) -> Result<Recording, String> {
    let w = &rig.wiring;
    if loopback.len() != drive.len() {
        return Err(format!("a loopback of {} samples for a drive of {}", loopback.len(), drive.len()));
    }
    let mut channels = vec![vec![0.0; drive.len()]; w.audio_channels as usize];
    let channel = *w.actuator_channels.get(actuator).ok_or("no such actuator")? as usize;
    let loopback_channel = w.loopback_channel as usize;
    channels.get_mut(channel).ok_or("actuator channel beyond the opened channels")?.copy_from_slice(drive);
    channels.get_mut(loopback_channel).ok_or("loopback channel beyond the opened channels")?.copy_from_slice(loopback);
    rig.play_and_record(&channels, record_samples).map_err(|e| e.to_string())
}
