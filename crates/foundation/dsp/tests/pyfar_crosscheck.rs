//! Independent cross-check of our DSP against pyfar, an established acoustics package.
//!
//! The fixtures in `tests/fixtures/pyfar/` were made once by `make_fixtures.py` (pyfar and numpy versions are in each
//! file's `meta` and in the README); CI only reads them. Each test runs our code on the very inputs pyfar saw and
//! asserts agreement where the two definitions coincide. Where they differ, the comment says how and the comparison is
//! restricted to what coincides, or one side is transformed into the other explicitly.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::PathBuf;

use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::{DeconvConfig, RINGING_GUARD_CYCLES, deconvolve, divide_spectra};
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::{KirkebyConfig, RegularisationProfile, TargetPhase, design_spectrum};
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use num_complex::Complex64;
use serde::Deserialize;

/// The generator's provenance, present in every fixture file.
#[derive(Debug, Deserialize)]
struct Meta {
    pyfar: String,
    numpy: String,
}

fn fixture_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pyfar").join(name)
}

fn load<T: for<'de> Deserialize<'de>>(name: &str) -> T {
    let path = fixture_path(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("parsing {}: {e}", path.display()))
}

/// Largest absolute sample difference; the lengths must match.
fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "length mismatch");
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

// --- sweeps ---------------------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
struct SweepFixture {
    meta: Meta,
    cases: Vec<SweepCase>,
}

#[derive(Debug, Deserialize)]
struct SweepCase {
    name: String,
    kind: String,
    f1_hz: f64,
    f2_hz: f64,
    amplitude: f64,
    sample_rate_hz: f64,
    n_samples: usize,
    /// Our half-Hann fade-out length; pyfar's `n_fade_out` is this plus one (see `make_fixtures.py`).
    fade_out_samples: usize,
    samples: Vec<f64>,
}

impl SweepCase {
    /// Our spec for the same sweep. pyfar's duration is `T = n_samples / sample_rate`, so `duration_s` is exactly
    /// that (here 2000 / 8000 = 0.25 s, exact in binary), and ours has the same `round(T fs)` samples.
    fn spec(&self) -> SweepSpec {
        let kind = match self.kind.as_str() {
            "linear" => SweepKind::Linear,
            "exponential" => SweepKind::Exponential,
            other => panic!("unknown sweep kind {other}"),
        };
        SweepSpec {
            kind,
            f1_hz: self.f1_hz,
            f2_hz: self.f2_hz,
            duration_s: self.n_samples as f64 / self.sample_rate_hz,
            sample_rate_hz: self.sample_rate_hz,
            amplitude: self.amplitude,
            // pyfar's time-domain sweeps have no fade-in at all.
            fade_in_s: 0.0,
            fade_out_s: self.fade_out_samples as f64 / self.sample_rate_hz,
        }
    }
}

/// Both sweep formulas are identical to ours (pyfar: Farina 2000; linear `sin(2 pi f1 t + 2 pi (f2 - f1) / T t^2 / 2)`,
/// exponential `sin(2 pi f1 L (e^(t / L) - 1))`, `L = T / ln(f2 / f1)`, `t = i / fs`, `T = n / fs`), amplitude is a
/// plain factor on both sides, and pyfar's squared-cosine fade-out of `m + 1` samples is our half-Hann fade of `m`.
///
/// Tolerance 1e-9 (absolute, amplitudes <= 1): the phases reach about 2.4e3 rad, where one rounding costs ~5e-13 rad,
/// and ours uses `exp_m1` where pyfar uses `exp - 1` (a few ulps of e^(t/L) <= 4000, times 2 pi f1 L: < 1e-11 rad).
/// 1e-9 is a hundredfold margin over that, yet far below any real convention difference: a duration off by one
/// sample changes samples by 0.1 or more (checked by the next test).
#[test]
fn sweeps_match_pyfar_sample_by_sample() {
    let fixture: SweepFixture = load("sweeps.json");
    assert!(!fixture.meta.pyfar.is_empty() && !fixture.meta.numpy.is_empty());
    assert_eq!(fixture.cases.len(), 6, "one case per kind x {{plain, fade-out, band extremes}}");
    for case in &fixture.cases {
        let ours = case.spec().generate().unwrap();
        assert_eq!(ours.len(), case.samples.len(), "{}: length", case.name);
        let err = max_abs_diff(&ours, &case.samples);
        eprintln!("sweep {}: max |ours - pyfar| = {err:.3e}", case.name);
        assert!(err < 1e-9, "{}: max |ours - pyfar| = {err:e}", case.name);
        // The fixture is not trivially small: it actually swings to its amplitude.
        let peak = case.samples.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
        assert!(peak > 0.9 * case.amplitude, "{}: peak {peak}", case.name);
    }
}

/// The sample comparison above can fail: the same sweep one sample longer (`T = (n + 1) / fs`, a plausible off-by-one
/// in the duration convention) departs from pyfar's by far more than the 1e-9 tolerance.
#[test]
fn sweep_comparison_detects_an_off_by_one_duration() {
    let fixture: SweepFixture = load("sweeps.json");
    for case in &fixture.cases {
        let spec = case.spec();
        let longer = SweepSpec { duration_s: (case.n_samples + 1) as f64 / case.sample_rate_hz, ..spec };
        let mut ours = longer.generate().unwrap();
        ours.truncate(case.n_samples);
        let err = max_abs_diff(&ours, &case.samples);
        eprintln!("sweep {}: off-by-one duration gives max |diff| = {err:.3}", case.name);
        assert!(err > 0.1 * case.amplitude, "{}: off-by-one went unnoticed ({err:e})", case.name);
    }
}

// --- shared fixture pieces -------------------------------------------------------------------------------------------

/// Our band limit, as stored in a fixture.
#[derive(Debug, Deserialize)]
struct Band {
    lo_hz: f64,
    hi_hz: f64,
    lo_transition_hz: f64,
    hi_transition_hz: f64,
}

impl Band {
    fn limit(&self) -> BandLimit {
        BandLimit::new(self.lo_hz, self.hi_hz, self.lo_transition_hz, self.hi_transition_hz).unwrap()
    }
}

/// Where pyfar's cross-faded regularisation is pure: "outside" below `outside_below` and from `outside_from` on,
/// "inside" from `inside_from` to before `inside_to` (bin indices). Between them pyfar cross-fades with sin^2 over
/// bins, a shape our raised-cosine skirts (in Hz) do not share.
#[derive(Debug, Deserialize)]
struct PureBins {
    outside_below: usize,
    inside_from: usize,
    inside_to: usize,
    outside_from: usize,
}

impl PureBins {
    fn is_inside(&self, k: usize) -> bool {
        (self.inside_from..self.inside_to).contains(&k)
    }

    fn is_outside(&self, k: usize) -> bool {
        k < self.outside_below || k >= self.outside_from
    }
}

/// `|a - b|` relative to the largest magnitude of `b`, over the bins `keep` selects; also returns how many it kept.
fn max_rel_diff(a: &[Complex64], b: &[Complex64], keep: impl Fn(usize) -> bool) -> (f64, usize) {
    assert_eq!(a.len(), b.len(), "bin count mismatch");
    let scale = b.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let (mut err, mut kept) = (0.0f64, 0);
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        if keep(k) {
            err = err.max((x - y).norm() / scale);
            kept += 1;
        }
    }
    (err, kept)
}

// --- deconvolution ---------------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
struct DeconvFixture {
    sample_rate_hz: f64,
    excitation: Vec<f64>,
    recording: Vec<f64>,
    /// Our `deconvolve` FFT length without a band; also the length of the spectral comparisons.
    n_fft: usize,
    /// `RINGING_GUARD_CYCLES` as `make_fixtures.py` replicated it.
    ringing_guard_cycles: f64,
    /// The band limit's ringing guard, samples, as `make_fixtures.py` computed it.
    ringing_guard_samples: usize,
    /// Our `deconvolve` FFT length with the band: `n_fft`'s minimum plus the guard, rounded up to a fast length.
    n_fft_band: usize,
    ir_len: usize,
    regularisation: f64,
    band: Band,
    pyfar_pure_bins: PureBins,
    /// pyfar's `deconvolve` given our `eps` (band case) as `regu_final` at every bin: `n_fft_band` samples.
    same_eps_band: Vec<f64>,
    /// The same with our `eps` for no band (maximum over all bins): `n_fft` samples.
    same_eps_full: Vec<f64>,
    /// pyfar's frequency-range regularisation with `regu_inside` = our regularisation, `regu_outside` = 1.
    range_regu_inside_ours: Vec<f64>,
    /// pyfar's frequency-range regularisation with its default `regu_inside` (-200 dB).
    range_regu_inside_default: Vec<f64>,
    pyfar_default_regu_inside: f64,
}

impl DeconvFixture {
    fn config(&self, band: Option<BandLimit>) -> DeconvConfig {
        DeconvConfig {
            sample_rate_hz: self.sample_rate_hz,
            ir_len: self.ir_len,
            band,
            regularisation: self.regularisation,
            pre_samples: 0,
        }
    }

    fn gains(&self) -> Vec<f64> {
        self.band.limit().bin_gains(self.n_fft, self.sample_rate_hz)
    }

    /// The FFT length our `deconvolve` uses, worked out here independently the way `deconv.rs` documents it:
    /// `fast_len(max(recording, excitation + ir_len) + guard)`, the guard being `ceil(RINGING_GUARD_CYCLES fs / W)`
    /// for the narrowest non-zero skirt width `W` with a band, 0 without. Returns `(guard, n)`.
    fn our_fft_len(&self, band: Option<&Band>) -> (usize, usize) {
        let guard = band.map_or(0, |b| {
            let narrowest_hz =
                [b.lo_transition_hz, b.hi_transition_hz].into_iter().filter(|w| *w > 0.0).fold(f64::INFINITY, f64::min);
            assert!(narrowest_hz.is_finite(), "the fixture's band has skirts");
            (RINGING_GUARD_CYCLES * self.sample_rate_hz / narrowest_hz).ceil() as usize
        });
        let min_len = self.recording.len().max(self.excitation.len() + self.ir_len);
        (guard, fft::fast_len(min_len + guard).unwrap())
    }
}

/// Our `deconvolve` is pyfar's `deconvolve` (`H = Y X* / (|X|^2 + eps)`, both zero-padded to one FFT length, time 0
/// at the excitation's first sample) when pyfar is handed our `eps = regularisation * max |X|^2` (maximum over the
/// bins our band keeps) as `regu_final`; ours then multiplies by the band gains and keeps `ir_len` samples. Without a
/// band the first `ir_len` samples must agree directly; with one, pyfar's spectrum is multiplied by our gains here
/// (explicitly, the one step pyfar does not have) before comparing.
///
/// Both sides must use the same FFT length, since it sets the bins, the band gains and `max |X|^2`. With a band ours
/// adds a ringing guard (`deconv.rs`, `ringing_guard`: 8 periods of the narrowest skirt, here 8 x 8000 / 50 = 1280
/// samples), so pyfar was run at 2160 without the band and at 3456 with it; both lengths are checked against our
/// convention first, so a change of that convention fails here with its own message, not as a numeric mismatch.
///
/// Tolerance 1e-10 of the response's peak: the two sides do the same arithmetic through different FFTs (pocketfft
/// and rustfft at n = 2160 and 3456), each accurate to ~1e-15 relative; the division is well conditioned everywhere (`eps`
/// bounds the gain at `1 / (2 sqrt(eps))`), so the difference stays near 1e-14. A wrong time origin, padding or
/// `eps` would show at 1e-3 or more.
#[test]
fn deconvolve_matches_pyfar_given_the_same_regularisation() {
    let fx: DeconvFixture = load("deconvolution.json");
    // Our FFT length convention is what pyfar was given: no band, fast length of max(recording, excitation + ir_len).
    let (_, n) = fx.our_fft_len(None);
    assert_eq!(n, fx.n_fft, "our deconvolve's FFT length without a band changed: regenerate the pyfar fixtures");
    assert_eq!(fx.same_eps_full.len(), n);

    let ours = deconvolve(&fx.recording, &fx.excitation, &fx.config(None)).unwrap();
    let peak = fx.same_eps_full.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let err = max_abs_diff(&ours, &fx.same_eps_full[..fx.ir_len]) / peak;
    eprintln!("deconvolve, no band: max |ours - pyfar| / peak = {err:.3e}");
    assert!(err < 1e-10, "no band: relative error {err:e}");

    // With our band: the FFT length grows by the ringing guard, which make_fixtures.py replicated.
    assert_eq!(
        RINGING_GUARD_CYCLES, fx.ringing_guard_cycles,
        "deconv::RINGING_GUARD_CYCLES changed: update make_fixtures.py and regenerate the pyfar fixtures"
    );
    let (guard, n_band) = fx.our_fft_len(Some(&fx.band));
    assert_eq!(
        (guard, n_band),
        (fx.ringing_guard_samples, fx.n_fft_band),
        "our band-limited FFT length (ringing guard, length) differs from the fixture's: regenerate the pyfar fixtures"
    );
    assert_eq!(fx.same_eps_band.len(), n_band);
    // pyfar's spectrum times our gains, back to time, first ir_len samples.
    let pyfar_spec = fft::forward(&fx.same_eps_band, n_band).unwrap();
    let gains = fx.band.limit().bin_gains(n_band, fx.sample_rate_hz);
    let limited: Vec<Complex64> = pyfar_spec.iter().zip(gains).map(|(c, g)| c * g).collect();
    let pyfar_limited = fft::inverse(&limited, n_band).unwrap();
    let ours = deconvolve(&fx.recording, &fx.excitation, &fx.config(Some(fx.band.limit()))).unwrap();
    let peak = pyfar_limited.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let err = max_abs_diff(&ours, &pyfar_limited[..fx.ir_len]) / peak;
    eprintln!("deconvolve, band-limited: max |ours - pyfar x gains| / peak = {err:.3e}");
    assert!(err < 1e-10, "band: relative error {err:e}");
}

/// pyfar's own regularisation for `deconvolve` is frequency dependent: `regu_inside * max |X|^2` in its frequency
/// range, `regu_outside * max |X|^2` beyond it, cross-faded with sin^2 over the bins from `lo / sqrt 2` to `lo` and
/// from `hi` to `hi sqrt 2`, and no band gains. Ours is one `eps` everywhere, then raised-cosine band gains. The two
/// coincide where pyfar is purely "inside" and our gain is exactly 1, given `regu_inside` = our `regularisation` and
/// the same `max |X|^2` (pyfar takes it over all bins, ours over the band's bins: the same here, since a sweep's
/// strongest bin lies in its band; if it did not, this test would fail at the 1e-3 level).
///
/// Tolerance 1e-10 of the largest in-band bin: the same formula through two FFT libraries (see above).
/// Beyond the skirts the definitions differ on purpose: ours is exactly 0, pyfar's is merely regularised.
#[test]
fn divide_spectra_matches_pyfar_frequency_range_regularisation_in_band() {
    let fx: DeconvFixture = load("deconvolution.json");
    let n = fx.n_fft;
    let gains = fx.gains();
    let num = fft::forward(&fx.recording, n).unwrap();
    let den = fft::forward(&fx.excitation, n).unwrap();
    let ours = divide_spectra(&num, &den, Some(&gains), fx.regularisation).unwrap();
    let pyfar = fft::forward(&fx.range_regu_inside_ours, n).unwrap();
    let pure = &fx.pyfar_pure_bins;
    let (err, kept) = max_rel_diff(&ours, &pyfar, |k| pure.is_inside(k) && gains[k] == 1.0);
    eprintln!("divide_spectra vs pyfar frequency range, in band: {kept} bins, max rel error {err:.3e}");
    // 100 to 3000 Hz at 8000 / 2160 Hz per bin: about 780 bins.
    assert!(kept > 750, "only {kept} bins compared");
    assert!(err < 1e-10, "in-band relative error {err:e}");

    // Where they differ: beyond our skirts ours is 0 and pyfar's is not.
    let beyond: Vec<usize> = (0..gains.len()).filter(|&k| gains[k] == 0.0 && pure.is_outside(k)).collect();
    assert!(!beyond.is_empty());
    assert!(beyond.iter().all(|&k| ours[k] == Complex64::new(0.0, 0.0)));
    assert!(beyond.iter().any(|&k| pyfar[k].norm() > 0.0));
}

/// With pyfar's default `regu_inside` (1e-10, -200 dB) and ours at 1e-3 the definitions differ in band too; the
/// difference is known exactly. In band both are `Y X* / (|X|^2 + eps)` with the same `Y X*`, so their ratio is the
/// real, positive `(|X|^2 + 1e-10 M) / (|X|^2 + 1e-3 M)` (M = max |X|^2): the phases agree and, where the sweep has
/// `|X|^2 >= 0.1 M` (the bulk of its band), the magnitudes agree within `20 log10(1 + 1e-3 / 0.1)` = 0.0864 dB.
///
/// Tolerances: phase 1e-9 rad (rounding of the same complex product, far below any convention difference); magnitude
/// 0.0864 dB plus 1e-9 dB of rounding. The measured figure is printed.
#[test]
fn deconvolution_in_band_within_stated_db_of_pyfar_default_regularisation() {
    let fx: DeconvFixture = load("deconvolution.json");
    assert_eq!(fx.pyfar_default_regu_inside, 1e-10);
    let n = fx.n_fft;
    let gains = fx.gains();
    let num = fft::forward(&fx.recording, n).unwrap();
    let den = fft::forward(&fx.excitation, n).unwrap();
    let ours = divide_spectra(&num, &den, Some(&gains), fx.regularisation).unwrap();
    let pyfar = fft::forward(&fx.range_regu_inside_default, n).unwrap();
    let peak_power = den.iter().map(Complex64::norm_sqr).fold(0.0, f64::max);
    let bound_db = 20.0 * (1.0 + fx.regularisation / 0.1).log10();
    let pure = &fx.pyfar_pure_bins;
    let (mut worst_db, mut worst_phase, mut kept) = (0.0f64, 0.0f64, 0usize);
    for k in 0..gains.len() {
        if pure.is_inside(k) && gains[k] == 1.0 && den[k].norm_sqr() >= 0.1 * peak_power {
            let ratio = ours[k] / pyfar[k];
            worst_db = worst_db.max((20.0 * ratio.norm().log10()).abs());
            worst_phase = worst_phase.max(ratio.arg().abs());
            kept += 1;
        }
    }
    eprintln!(
        "vs pyfar default regularisation: {kept} bins, worst {worst_db:.4} dB (bound {bound_db:.4}), \
         phase {worst_phase:.2e} rad"
    );
    assert!(kept > 700, "only {kept} bins compared");
    assert!(worst_db <= bound_db + 1e-9, "{worst_db} dB exceeds {bound_db} dB");
    assert!(worst_phase < 1e-9, "phase differs by {worst_phase} rad");
    // The bound is not vacuous: the regularisations do differ by a visible amount somewhere.
    assert!(worst_db > 1e-3, "{worst_db} dB: the two regularisations should differ");
}

// --- regularised spectrum inversion (Kirkeby) ------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
struct InversionFixture {
    sample_rate_hz: f64,
    response: Vec<f64>,
    n_fft: usize,
    beta: f64,
    band: Band,
    in_band: f64,
    out_of_band: f64,
    modelling_delay_samples: usize,
    pyfar_within: f64,
    pyfar_beta_value: f64,
    pyfar_pure_bins: PureBins,
    our_profile_inverse_re: Vec<f64>,
    our_profile_inverse_im: Vec<f64>,
    our_profile_regularisation: Vec<f64>,
    pyfar_profile_inverse_re: Vec<f64>,
    pyfar_profile_inverse_im: Vec<f64>,
}

fn complex(re: &[f64], im: &[f64]) -> Vec<Complex64> {
    assert_eq!(re.len(), im.len());
    re.iter().zip(im).map(|(&r, &i)| Complex64::new(r, i)).collect()
}

impl InversionFixture {
    fn config(&self, in_band: f64, out_of_band: f64, modelling_delay_samples: usize) -> KirkebyConfig {
        KirkebyConfig {
            sample_rate_hz: self.sample_rate_hz,
            fir_len: self.n_fft,
            modelling_delay_samples,
            response_delay_samples: 0,
            beta: self.beta,
            profile: RegularisationProfile { band: self.band.limit(), in_band, out_of_band },
            // A pure-delay target: pyfar has no minimum-phase target, and the brief compares before any phase step.
            target: TargetPhase::Linear,
            fft_len: Some(self.n_fft),
        }
    }
}

/// pyfar's `RegularizedSpectrumInversion` computes `S* D / (|S|^2 + beta |eps|^2)`; our `design_spectrum` computes
/// `C* D / (|C|^2 + beta max|C|^2 B)`. The fixture hands pyfar our profile as `eps = sqrt(B)`, `beta = beta max|C|^2`
/// (numeric) and our modelling delay as its target (an impulse delayed by the same samples), so the two are one
/// formula at every bin, delay sign included. Compared: the complex inverse before our truncation and tapering, and
/// the absolute regularisation `beta_abs B` itself.
///
/// Tolerances: inverse 1e-10 of its peak (same arithmetic through different FFTs, ~1e-15 each, and a well-conditioned
/// division); regularisation 1e-12 relative per bin (a product of the same cosine and the same peak power, only
/// rounding apart). A delay of the wrong sign or a profile off by a bin would show at order 1.
#[test]
fn kirkeby_design_spectrum_matches_pyfar_given_our_profile() {
    let fx: InversionFixture = load("inversion.json");
    let cfg = fx.config(fx.in_band, fx.out_of_band, fx.modelling_delay_samples);
    let ours = design_spectrum(&fx.response, &cfg).unwrap();
    assert_eq!(ours.fft_len, fx.n_fft);
    let pyfar = complex(&fx.our_profile_inverse_re, &fx.our_profile_inverse_im);
    let (err, kept) = max_rel_diff(&ours.inverse, &pyfar, |_| true);
    eprintln!("Kirkeby vs pyfar (our profile): {kept} bins, max rel error {err:.3e}");
    assert_eq!(kept, fx.n_fft / 2 + 1);
    assert!(err < 1e-10, "inverse relative error {err:e}");

    let reg_err = ours
        .regularisation
        .iter()
        .zip(&fx.our_profile_regularisation)
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0.0, f64::max);
    eprintln!("Kirkeby vs pyfar (our profile): regularisation max rel error {reg_err:.3e}");
    assert!(reg_err < 1e-12, "regularisation relative error {reg_err:e}");
    // The fixture's pyfar beta is ours made absolute: beta * max |C|^2.
    let peak_power = ours.response.iter().map(Complex64::norm_sqr).fold(0.0, f64::max);
    assert!((fx.pyfar_beta_value / (fx.beta * peak_power) - 1.0).abs() < 1e-12);
}

/// pyfar's own frequency-range profile: `eps = within` in the band, 1 beyond it, cross-faded as
/// `within cos^2 + sin^2` over the bins from `lo / sqrt 2` to `lo` and from `hi` to `hi sqrt 2`; the inversion adds
/// `beta |eps|^2`. Ours with `in_band = within^2`, `out_of_band = 1`, the same beta and raised-cosine skirts over the
/// same frequency spans is the same formula wherever both profiles are flat: where pyfar is purely inside or outside
/// and our gain is exactly 1 or 0. There the complex spectra must agree (tolerance 1e-10 of the peak, as above).
///
/// In the cross-fades the shapes differ (pyfar's is sin^2 in bins applied to `eps`, then squared; ours a raised cosine
/// in Hz applied to `B`), but both regularisations stay between their in-band and out-of-band values and both
/// inverses are positive real multiples of `C*`. So there the phases must agree (1e-9 rad) and each magnitude must
/// lie between those of the two flat regularisations (with 1e-12 relative slack for rounding).
#[test]
fn kirkeby_matches_pyfar_frequency_range_profile_where_both_are_flat() {
    let fx: InversionFixture = load("inversion.json");
    let within_sq = fx.pyfar_within * fx.pyfar_within;
    let cfg = fx.config(within_sq, 1.0, 0);
    let ours = design_spectrum(&fx.response, &cfg).unwrap();
    let pyfar = complex(&fx.pyfar_profile_inverse_re, &fx.pyfar_profile_inverse_im);
    let gains = fx.band.limit().bin_gains(fx.n_fft, fx.sample_rate_hz);
    let pure = &fx.pyfar_pure_bins;
    let flat = |k: usize| (pure.is_inside(k) && gains[k] == 1.0) || (pure.is_outside(k) && gains[k] == 0.0);
    let (err, kept) = max_rel_diff(&ours.inverse, &pyfar, flat);
    eprintln!("Kirkeby vs pyfar (pyfar profile), flat bins: {kept}, max rel error {err:.3e}");
    // 513 bins less the two cross-fades (9 and 106 bins) and the bins where the edges' rounding differs.
    assert!(kept > 380, "only {kept} bins compared");
    assert!(err < 1e-10, "flat-region relative error {err:e}");

    let peak_power = ours.response.iter().map(Complex64::norm_sqr).fold(0.0, f64::max);
    let (r_in, r_out) = (fx.pyfar_beta_value * within_sq, fx.pyfar_beta_value);
    let (mut worst_phase, mut worst_db, mut fades) = (0.0f64, 0.0f64, 0usize);
    for k in (0..pyfar.len()).filter(|&k| !flat(k)) {
        let c = ours.response[k];
        let (lo, hi) = (c.norm() / (c.norm_sqr() + r_out), c.norm() / (c.norm_sqr() + r_in));
        for h in [ours.inverse[k], pyfar[k]] {
            assert!(h.norm() >= lo * (1.0 - 1e-12) && h.norm() <= hi * (1.0 + 1e-12), "bin {k}: |H| out of bounds");
        }
        let ratio = ours.inverse[k] / pyfar[k];
        worst_phase = worst_phase.max(ratio.arg().abs());
        worst_db = worst_db.max((20.0 * ratio.norm().log10()).abs());
        fades += 1;
    }
    eprintln!(
        "Kirkeby vs pyfar (pyfar profile), cross-fade bins: {fades}, worst {worst_db:.2} dB, \
         phase {worst_phase:.2e} rad"
    );
    assert!(fades > 0);
    assert!(worst_phase < 1e-9, "cross-fade phase differs by {worst_phase} rad");
    assert!((fx.pyfar_beta_value / (fx.beta * peak_power) - 1.0).abs() < 1e-12);
}

#[derive(Debug, Deserialize)]
struct SmoothingCase {
    name: String,
    num_fractions: f64,
    magnitude: Vec<f64>,
    n_window: usize,
    smoothed: Vec<f64>,
}

#[derive(Debug, Deserialize)]
struct SmoothingFixture {
    #[allow(dead_code)] // provenance, checked by the generator
    meta: Meta,
    cases: Vec<SmoothingCase>,
}

#[test]
fn standard_smoothing_matches_pyfars_smooth_fractional_octave() {
    // Same algorithm (Tylka et al. 2017, method 2) and the same not-a-knot cubic spline as scipy's `interp1d`: the
    // only differences are the order of floating-point operations (Thomas' algorithm against scipy's banded solver,
    // a running sum against numpy's average): 1e-15 to 3e-15 of the peak over 1001 bins; 1e-9 leaves room for
    // another BLAS.
    let fixture: SmoothingFixture = load("smoothing.json");
    assert_eq!(fixture.cases.len(), 6);
    for case in &fixture.cases {
        let (ours, n_window) =
            metaplate_dsp::smooth::fractional_octave_standard(&case.magnitude, case.num_fractions).unwrap();
        assert_eq!(n_window, case.n_window, "{}", case.name);
        let peak = case.smoothed.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = max_abs_diff(&ours, &case.smoothed);
        assert!(diff < 1e-9 * peak, "{}: {diff} against a peak of {peak}", case.name);
    }
}
