//! From the recipes' [`DaqConfig`] (inputs, ranges in volts, a rate in Hz) to the U6's StreamConfig.

use metaplate_core::daq::{DaqConfig, DaqError};
use metaplate_u6_protocol::config::MAX_SAMPLES_PER_PACKET;
use metaplate_u6_protocol::{Gain, StreamChannel, StreamConfig, scan_timing};

/// Converts `config` to the StreamConfig the driver sends, and checks it as the device would.
///
/// Every channel is single-ended (a `DaqChannel` names one input); its range must be one the U6 offers (+/-10, 1,
/// 0.1 or 0.01 V); the rate must be one the stream clock gives exactly (a whole number of ticks of 48 MHz, 4 MHz
/// or either divided by 256, for example 24 kHz = 48 MHz / 2000). SamplesPerPacket is the largest multiple of the
/// channel count up to 25, so that every packet holds whole scans.
///
/// # Errors
/// [`DaqError::Config`] naming what the U6 cannot do: a range it lacks, a rate its clock cannot make, 0 or more than
/// 25 channels, an input beyond AIN13, an aggregate rate over 50 kS/s, a block of 0 samples.
pub fn to_stream_config(
    config: &DaqConfig,
    resolution_index: u8,
    settling_factor: u8,
) -> Result<StreamConfig, DaqError> {
    let bad = |detail: String| DaqError::Config { detail };
    let n = config.channels.len();
    if n == 0 || n > usize::from(MAX_SAMPLES_PER_PACKET) {
        return Err(bad(format!("{n} channels: the U6 streams 1 to 25")));
    }
    if config.block_len_samples == 0 {
        return Err(bad("a block of 0 samples".into()));
    }
    let channels = config
        .channels
        .iter()
        .map(|ch| {
            let gain = Gain::for_range_v(ch.range_v).ok_or_else(|| {
                bad(format!(
                    "range {} V on input {} is not one of the U6's +/-10, 1, 0.1, 0.01 V",
                    ch.range_v, ch.input
                ))
            })?;
            Ok(StreamChannel { positive: ch.input, gain, differential: false })
        })
        .collect::<Result<Vec<_>, DaqError>>()?;
    let (clock, divide_by_256, scan_interval) = scan_timing(config.sample_rate_hz).ok_or_else(|| {
        bad(format!(
            "{} scans/s is not a rate the U6's stream clock makes exactly (48 MHz, 4 MHz, or either / 256, over a \
             whole ScanInterval of 1-65535)",
            config.sample_rate_hz
        ))
    })?;
    // 1..=25 channels: the quotient is at least 1 and the product at most 25.
    let samples_per_packet = (MAX_SAMPLES_PER_PACKET / n as u8) * n as u8;
    let stream = StreamConfig {
        resolution_index,
        samples_per_packet,
        settling_factor,
        clock,
        divide_by_256,
        scan_interval,
        channels,
    };
    stream.check().map_err(|e| bad(e.to_string()))?;
    Ok(stream)
}
