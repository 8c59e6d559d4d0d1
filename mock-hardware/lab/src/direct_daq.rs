//! The DAQ of a scene whose converter the 16-bit wire protocol cannot carry: another resolution, an ideal converter
//! (`daq.bits = 0`), or no clipping (`daq.clipping = false`), as error budgets ask for. It reads the lab's signals
//! in process, on the lab's clock, as the mock DAQ device would, and digitises them as the scene says. It has no
//! USB link, so the link's faults (stalls, overruns, disconnects) do not reach it.

use metaplate_core::daq::{BlockIntegrity, Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};

use crate::chain::Shared;

/// The in-process DAQ (see the module documentation).
pub(crate) struct DirectDaq {
    identity: DaqIdentity,
    shared: Shared,
    /// Resolution, bits; 0: no quantisation.
    bits: u32,
    clipping: bool,
    config: Option<DaqConfig>,
    /// Next sample index of the running acquisition.
    next_sample: Option<u64>,
}

impl DirectDaq {
    pub fn new(shared: Shared, bits: u32, clipping: bool) -> Self {
        let identity = DaqIdentity {
            vendor: "metaplate".into(),
            model: format!("mock lab direct DAQ ({} bit{})", bits, if clipping { "" } else { ", no clipping" }),
            serial: "LAB-DAQ-DIRECT".into(),
            firmware: env!("CARGO_PKG_VERSION").into(),
        };
        Self { identity, shared, bits, clipping, config: None, next_sample: None }
    }

    /// `volts` digitised on a channel of range `range_v`: rounded to the nearest of `2^bits` codes spanning
    /// `-range_v ..` in steps of `range_v / 2^(bits - 1)` (the wire protocol's rule at 16 bits) unless `bits` is 0,
    /// held at the rails when clipping is on. Returns the value and whether it sits on a rail (clipping on).
    fn digitise(&self, volts: f64, range_v: f64) -> (f64, bool) {
        let (value, top) = if self.bits == 0 {
            (volts, range_v)
        } else {
            let step = range_v / f64::from(self.bits - 1).exp2();
            ((volts / step).round() * step, range_v - step)
        };
        // On a rail or beyond it counts as clipped, as a sample on an extreme code does (the vibrometer's own
        // clipping lands exactly on the rail).
        let on_rail = value <= -range_v || value >= top;
        if self.clipping { (value.clamp(-range_v, top), on_rail) } else { (value, false) }
    }
}

impl Daq for DirectDaq {
    fn identity(&self) -> &DaqIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if self.next_sample.is_some() {
            return Err(DaqError::Protocol { detail: "configure while running".into() });
        }
        let bad = |detail: String| Err(DaqError::Config { detail });
        if config.channels.is_empty() {
            return bad("no channel".into());
        }
        if let Some(c) = config.channels.iter().find(|c| !(c.range_v.is_finite() && c.range_v > 0.0)) {
            return bad(format!("input {}: range {} V", c.input, c.range_v));
        }
        if !(config.sample_rate_hz.is_finite() && config.sample_rate_hz > 0.0) {
            return bad(format!("sample rate {} Hz", config.sample_rate_hz));
        }
        if config.block_len_samples == 0 {
            return bad("a block of 0 samples".into());
        }
        self.config = Some(config.clone());
        Ok(())
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.config.is_none() {
            return Err(DaqError::Protocol { detail: "start before configure".into() });
        }
        if self.next_sample.is_some() {
            return Err(DaqError::Protocol { detail: "already running".into() });
        }
        self.shared.lock().map_err(|e| DaqError::Device { code: -1, detail: e.to_string() })?.daq_started();
        self.next_sample = Some(0);
        Ok(())
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        let (Some(first), Some(config)) = (self.next_sample, self.config.as_ref()) else {
            return Err(DaqError::Protocol { detail: "read before start".into() });
        };
        let n = config.block_len_samples as usize;
        let mut volts = Vec::with_capacity(config.channels.len());
        let mut clipped = false;
        {
            let mut state = self.shared.lock().map_err(|e| DaqError::Device { code: -1, detail: e.to_string() })?;
            for channel in &config.channels {
                let mut v = vec![0.0; n];
                state
                    .fill(channel.input, first, config.sample_rate_hz, &mut v)
                    .map_err(|e| DaqError::Device { code: -2, detail: e.to_string() })?;
                for x in &mut v {
                    if !x.is_finite() {
                        return Err(DaqError::Device { code: -3, detail: "a non-finite input voltage".into() });
                    }
                    let (d, c) = self.digitise(*x, channel.range_v);
                    *x = d;
                    clipped |= c;
                }
                volts.push(v);
            }
        }
        self.next_sample = Some(first + n as u64);
        Ok(DaqBlock {
            first_sample_index: first,
            volts,
            integrity: BlockIntegrity { packets_lost: 0, samples_missing: 0, overrun: false, clipped },
        })
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        self.next_sample = None;
        Ok(())
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.next_sample = None;
        Ok(())
    }
}
