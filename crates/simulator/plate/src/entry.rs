//! A cache entry: the Green's functions of one (scene physics, model options, band, duration, sample rate) for
//! every point a request may address and every actuator, from which any request with those settings is cut.
//!
//! **Slots.** Slot `i < grid.len()` is grid point `i`, slot `grid.len() + k` actuator k's driving point (the
//! indices of [`GreensRequest::points`]). A grid point off the plate has no response: its slot is absent.
//!
//! **Representation.** Each (slot, actuator) pair is stored either as its impulse response (`ir_len` samples) or
//! as its spectrum at the plan's band bins (`2 * bins` words: real and imaginary parts), whichever is shorter. Both
//! are exact: a response synthesised from stored spectra goes through the same code as a direct computation
//! ([`crate::greens::impulse_responses`]), so a cut equals [`PlateModel::greens_functions`] of the same request bit
//! for bit. For the mock lab's default (24 kHz, 0.5 s, 40 to 800 Hz: 12,000 samples against 1,396 bins) the
//! spectra are 4.3 times shorter; for the ground truth's (2 kHz, 0.5 s, 40 to 700 Hz: 1,000 samples against
//! 1,213 bins) the impulse responses are 2.4 times shorter.
//!
//! **Cost.** Every frequency bin is one sparse LU and one solve for all actuators whatever the points; reading
//! out another point is a few multiply-adds per bin and actuator. So the entry costs about what one request does
//! (the solves), plus the inverse FFTs when it stores impulse responses (short ones: that representation is chosen
//! only when the responses are shorter than the band's bins).

use num_complex::Complex64;

use crate::error::PlateError;
use crate::greens::{GreensFunctions, GreensRequest, SpectralPlan, check_bytes, impulse_responses};
use crate::model::PlateModel;

/// How an entry stores each (slot, actuator) response.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Representation {
    /// The impulse response, `ir_len` samples.
    ImpulseResponse,
    /// The spectrum at the plan's bins, `(re, im)` per bin, before the band gains.
    BandSpectrum,
}

impl Representation {
    /// The code stored in an entry file.
    pub(crate) fn code(self) -> u64 {
        match self {
            Self::ImpulseResponse => 0,
            Self::BandSpectrum => 1,
        }
    }

    /// The representation of a stored code; `None` for an unknown one.
    pub(crate) fn from_code(code: u64) -> Option<Self> {
        match code {
            0 => Some(Self::ImpulseResponse),
            1 => Some(Self::BandSpectrum),
            _ => None,
        }
    }

    /// The shorter representation for `plan`.
    pub(crate) fn shorter(plan: &SpectralPlan) -> Self {
        if plan.ir_len <= 2 * plan.bins.len() { Self::ImpulseResponse } else { Self::BandSpectrum }
    }
}

/// Everything about an entry but its responses: what a reader needs to cut a request from its blocks.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct EntryLayout {
    /// Sample rate of the responses, Hz.
    pub sample_rate_hz: f64,
    /// The frequency grid (FFT length, response length, band bins and gains).
    pub plan: SpectralPlan,
    /// How each pair is stored.
    pub representation: Representation,
    /// Number of actuators (every one is in each block, in scene order).
    pub actuator_count: usize,
    /// Per slot: whether it has a block (is on the plate).
    pub present: Vec<bool>,
}

impl EntryLayout {
    /// f64 words per (slot, actuator) pair.
    pub(crate) fn words_per_pair(&self) -> usize {
        match self.representation {
            Representation::ImpulseResponse => self.plan.ir_len,
            Representation::BandSpectrum => 2 * self.plan.bins.len(),
        }
    }

    /// f64 words per slot's block: every actuator's pair, in scene order.
    pub(crate) fn block_words(&self) -> usize {
        self.actuator_count * self.words_per_pair()
    }

    /// Whether every point and actuator of `request` is in the entry (and the lists are not empty): otherwise the
    /// request is computed directly, which reports what is wrong with it.
    pub(crate) fn serves(&self, request: &GreensRequest) -> bool {
        !request.points.is_empty()
            && !request.actuators.is_empty()
            && request.actuators.iter().all(|&a| a < self.actuator_count)
            && request.points.iter().all(|&p| self.present.get(p).copied().unwrap_or(false))
    }

    /// Cuts `request` (which the entry [serves](Self::serves)) from the blocks: `blocks[i]` is the block of
    /// `request.points[i]`. Impulse responses are copied; spectra are synthesised on `threads` threads.
    ///
    /// With a `target` (a plan and its sample rate) the responses are synthesised on that plan instead of the
    /// entry's own: `Ok(None)` unless the entry holds band spectra at every one of the target's bin frequencies, bit
    /// for bit (a request at another rate or band whose bins fall on the entry's). The responses then equal
    /// computing the request alone, bit for bit: the same solves, synthesised by the same code.
    ///
    /// # Errors
    /// [`PlateError::Dsp`] from the FFT; [`PlateError::NonFiniteResult`].
    pub(crate) fn cut(
        &self,
        request: &GreensRequest,
        blocks: &[&[f64]],
        target: Option<&Target>,
        threads: usize,
    ) -> Result<Option<GreensFunctions>, PlateError> {
        let per_pair = self.words_per_pair();
        let n_act = request.actuators.len();
        let pair_words = |pair: usize| {
            let (p, a) = (pair / n_act, request.actuators[pair % n_act]);
            &blocks[p][a * per_pair..(a + 1) * per_pair]
        };
        let n_pairs = request.points.len() * n_act;
        let (plan, sample_rate_hz, data) = match (self.representation, target) {
            (Representation::ImpulseResponse, None) => {
                let data = (0..n_pairs).flat_map(|pair| pair_words(pair).iter().copied()).collect();
                (&self.plan, self.sample_rate_hz, data)
            }
            (Representation::ImpulseResponse, Some(_)) => return Ok(None),
            (Representation::BandSpectrum, _) => {
                let (plan, rate) = target.map_or((&self.plan, self.sample_rate_hz), |t| (&t.plan, t.sample_rate_hz));
                let Some(bins) = self.plan.bins_at(plan) else { return Ok(None) };
                let data = impulse_responses(plan, rate, threads, n_pairs, &|pair, b| {
                    let words = pair_words(pair);
                    Complex64::new(words[2 * bins[b]], words[2 * bins[b] + 1])
                })?;
                (plan, rate, data)
            }
        };
        Ok(Some(GreensFunctions {
            sample_rate_hz,
            ir_len: plan.ir_len,
            points: request.points.clone(),
            actuators: request.actuators.clone(),
            data,
        }))
    }
}

/// A frequency grid to synthesise responses on other than an entry's own (see [`EntryLayout::cut`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Target {
    /// The request's own plan.
    pub plan: SpectralPlan,
    /// The request's sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// An entry in memory: its layout and the blocks of its present slots, in slot order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GreensEntry {
    /// What the blocks hold.
    pub layout: EntryLayout,
    /// `layout.block_words()` words per present slot, in slot order.
    pub data: Vec<f64>,
}

impl GreensEntry {
    /// Cuts `request` from the entry (on `target`'s plan when given); `Ok(None)` when the entry does not
    /// [serve](EntryLayout::serves) it or cannot give the target's bins.
    ///
    /// # Errors
    /// As [`EntryLayout::cut`].
    pub(crate) fn cut(
        &self,
        request: &GreensRequest,
        target: Option<&Target>,
        threads: usize,
    ) -> Result<Option<GreensFunctions>, PlateError> {
        if !self.layout.serves(request) {
            return Ok(None);
        }
        // Block index of each slot: the number of present slots before it.
        let mut rank = Vec::with_capacity(self.layout.present.len());
        let mut n = 0;
        for &present in &self.layout.present {
            rank.push(n);
            n += usize::from(present);
        }
        let words = self.layout.block_words();
        let blocks: Vec<&[f64]> =
            request.points.iter().map(|&p| &self.data[rank[p] * words..(rank[p] + 1) * words]).collect();
        self.layout.cut(request, &blocks, target, threads)
    }
}

impl PlateModel {
    /// The entry for `request`'s band, duration and sample rate (its points and actuators are ignored): every slot
    /// on the plate, every actuator, in the shorter representation.
    ///
    /// # Errors
    /// As [`PlateModel::greens_functions`] for the band, duration and rate; [`PlateError::TooLarge`] when the entry
    /// would need more than [`crate::MAX_GREENS_BYTES`] (a scene with a very large grid: the caller then computes
    /// the request alone).
    pub(crate) fn greens_entry(&self, request: &GreensRequest) -> Result<GreensEntry, PlateError> {
        let plan = SpectralPlan::new(request, &|f| self.loss_factor_bound(f))?;
        let weights = self.point_weights();
        let present: Vec<bool> = weights.iter().map(Option::is_some).collect();
        let points: Vec<&[(usize, f64)]> = weights.into_iter().flatten().collect();
        let actuators: Vec<usize> = (0..self.actuator_count()).collect();
        let representation = Representation::shorter(&plan);
        let n_pairs = points.len() * actuators.len();
        // The spectra, and the blocks built from them.
        let per_pair = match representation {
            Representation::ImpulseResponse => plan.ir_len as f64 * 8.0,
            Representation::BandSpectrum => plan.bins.len() as f64 * 16.0,
        };
        check_bytes(n_pairs as f64 * (plan.bins.len() as f64 * 16.0 + per_pair))?;
        let spectra = self.band_spectra(&plan, &actuators, &points)?;
        let data = match representation {
            Representation::ImpulseResponse => {
                impulse_responses(&plan, request.sample_rate_hz, self.options().threads, n_pairs, &|pair, b| {
                    spectra[b * n_pairs + pair]
                })?
            }
            Representation::BandSpectrum => {
                // A transpose from bin-major to pair-major, in tiles of pairs (each bin's row is read a tile at a
                // time rather than one value per pair).
                const TILE: usize = 32;
                let n_bins = plan.bins.len();
                let mut data = vec![0.0; n_pairs * 2 * n_bins];
                for (t, tile) in data.chunks_mut(TILE * 2 * n_bins).enumerate() {
                    for b in 0..n_bins {
                        for (i, words) in tile.chunks_mut(2 * n_bins).enumerate() {
                            let v = spectra[b * n_pairs + t * TILE + i];
                            words[2 * b] = v.re;
                            words[2 * b + 1] = v.im;
                        }
                    }
                }
                data
            }
        };
        let layout = EntryLayout {
            sample_rate_hz: request.sample_rate_hz,
            plan,
            representation,
            actuator_count: actuators.len(),
            present,
        };
        Ok(GreensEntry { layout, data })
    }
}
