use metaplate_dsp::band::BandLimit;
use metaplate_dsp::conv::convolve;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::error::DspError;
use metaplate_dsp::fft;
use metaplate_dsp::pipeline::*;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use num_complex::Complex64;

const FS: f64 = 24_000.0;

fn layout(repetitions: usize) -> RepetitionLayout {
    let spec =
        SweepSpec { kind: SweepKind::Linear, f1_hz: 200.0, f2_hz: 3000.0, duration_s: 0.2, ..SweepSpec::default() };
    RepetitionLayout { excitation: spec.generate().unwrap(), repetitions }
}

fn cfg() -> DeconvConfig {
    DeconvConfig {
        sample_rate_hz: FS,
        ir_len: 512,
        band: Some(BandLimit::new(300.0, 2500.0, 50.0, 200.0).unwrap()),
        regularisation: 1e-3,
        pre_samples: 0,
    }
}

#[test]
fn the_noise_energy_predicts_the_error_noise_leaves_in_the_response() {
    // A 450 Hz decaying tone through 6 repetitions, white noise on the velocity at three levels; the response
    // from the noisy recording against the one from the clean recording, within the error band (here 300..600
    // Hz: the excitation's band limit starts at 300), against the estimate. Averaged over 8 noise draws in
    // power: one draw's error over the ~7 bins of a 512-sample response in that band scatters by about 1.5 dB,
    // the mean of 8 by about 0.5 dB, so 1 dB is the bar.
    let l = layout(6);
    let ir: Vec<f64> =
        (0..300).map(|i| (-(i as f64) / 60.0).exp() * (std::f64::consts::TAU * 450.0 * i as f64 / FS).sin()).collect();
    let (clean_v, loopback) = acquisition(&l, 1000, 700, &ir);
    let clean = process_channel(&clean_v, &loopback, &l, &cfg()).unwrap();
    // No noise: the spread is rounding alone.
    assert!(clean.estimated_error_db(FS).is_some_and(|db| db < -200.0), "{:?}", clean.estimated_error_db(FS));
    for noise_rms in [1e-4, 1e-3, 1e-2] {
        let (mut measured, mut estimated) = (0.0, 0.0);
        for seed in 0..8u64 {
            let mut rng = metaplate_core::rng::SplitMix64::new(seed, 0);
            let noisy_v: Vec<f64> = clean_v.iter().map(|v| v + noise_rms * rng.normal()).collect();
            let noisy = process_channel(&noisy_v, &loopback, &l, &cfg()).unwrap();
            let diff: Vec<f64> = noisy.ir.iter().zip(&clean.ir).map(|(a, b)| a - b).collect();
            let band = metaplate_dsp::accuracy::ERROR_BAND_HZ;
            measured += metaplate_dsp::accuracy::band_energy(&diff, band, FS).unwrap()
                / metaplate_dsp::accuracy::band_energy(&clean.ir, band, FS).unwrap();
            estimated += 10f64.powf(noisy.estimated_error_db(FS).unwrap() / 10.0);
        }
        let (measured_db, estimated_db) = (10.0 * (measured / 8.0).log10(), 10.0 * (estimated / 8.0).log10());
        assert!(
            (measured_db - estimated_db).abs() < 1.0,
            "noise {noise_rms}: {measured_db:.2} vs {estimated_db:.2} dB"
        );
    }
    // One repetition: no spread, no estimate.
    let (v1, l1) = acquisition(&layout(1), 1000, 700, &ir);
    assert_eq!(process_channel(&v1, &l1, &layout(1), &cfg()).unwrap().noise_energy, None);
}

#[test]
fn a_two_sided_response_takes_the_precursor_from_the_end_of_the_period() {
    // A pure delay of 3 samples: band-limited, it rings on both sides of sample 3. The two-sided response is
    // the one-sided one shifted by pre_samples, with the precursor in front, and matches the band-limited truth
    // on both sides (the one-sided one misses the precursor).
    let l = layout(3);
    let mut ir = vec![0.0; 4];
    ir[3] = 0.5;
    let (velocity, loopback) = acquisition(&l, 1000, 700, &ir);
    let pre = 64;
    let one = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
    let two = process_channel(&velocity, &loopback, &l, &DeconvConfig { pre_samples: pre, ..cfg() }).unwrap();
    assert_eq!(two.ir.len(), 512);
    for (a, b) in one.ir[..512 - pre].iter().zip(&two.ir[pre..]) {
        assert!((a - b).abs() < 1e-12, "{a} {b}");
    }
    let precursor: f64 = two.ir[..pre].iter().map(|v| v * v).sum();
    assert!(precursor > 1e-6, "the band limit rings before time 0: {precursor:e}");
    // Against the band-limited truth, both sides of it.
    let err_two = two_sided_in_band_error(&two.ir, &ir, 4800, pre);
    assert!(err_two < BIAS_BOUND, "two-sided in-band error {err_two:e}");
}

/// Loopback: the copies from `latency` (whole samples, no drift), then `tail` samples of silence; velocity:
/// the loopback through `ir`.
fn acquisition(layout: &RepetitionLayout, latency: usize, tail: usize, ir: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = layout.excitation.len();
    let mut loopback = vec![0.0; latency];
    loopback.extend(layout.excitation.iter().cycle().take(n * layout.repetitions));
    loopback.extend(std::iter::repeat_n(0.0, tail));
    let mut velocity = convolve(&loopback, ir).unwrap();
    velocity.truncate(loopback.len());
    (velocity, loopback)
}

/// Relative in-band error energy of `ir` against `truth` band-limited like the pipeline does (the band's gains
/// on a length-n FFT) and truncated alike: the band limit's skirts ring for ~1 / 50 Hz, as long as the IR.
fn in_band_error(ir: &[f64], truth: &[f64], n: usize) -> f64 {
    two_sided_in_band_error(ir, truth, n, 0)
}

/// As [`in_band_error`] for an `ir` from time `-pre` on: both it and the reference are laid on the length-n
/// circle with time 0 first and the precursor wrapped to the end.
fn two_sided_in_band_error(ir: &[f64], truth: &[f64], n: usize, pre: usize) -> f64 {
    let g = cfg().band.unwrap().bin_gains(n, FS);
    let limited: Vec<Complex64> = fft::forward(truth, n).unwrap().iter().zip(&g).map(|(c, g)| c * g).collect();
    let period = fft::inverse(&limited, n).unwrap();
    let on_circle = |x: &[f64]| {
        let mut c = vec![0.0; n];
        c[..x.len() - pre].copy_from_slice(&x[pre..]);
        c[n - pre..].copy_from_slice(&x[..pre]);
        c
    };
    let mut reference_two_sided = period[n - pre..].to_vec();
    reference_two_sided.extend_from_slice(&period[..ir.len() - pre]);
    let reference = on_circle(&reference_two_sided);
    let diff: Vec<f64> = on_circle(ir).iter().zip(&reference).map(|(a, b)| a - b).collect();
    let (e, t) = (fft::forward(&diff, n).unwrap(), fft::forward(&reference, n).unwrap());
    let band = |k: &usize| (300.0..=2500.0).contains(&fft::bin_freq_hz(*k, n, FS));
    let err: f64 = (0..e.len()).filter(band).map(|k| e[k].norm_sqr()).sum();
    err / (0..t.len()).filter(band).map(|k| t[k].norm_sqr()).sum::<f64>()
}

/// The regularisation's bias on a flat response, eps / (|D|^2 + eps) with eps = 1e-3 max |D|^2, stays below
/// 1e-2 where this short sweep's power is above a tenth of its peak, true over 300..2500 Hz (its Fresnel ripple
/// is a few dB): a relative error energy below 1e-4.
const BIAS_BOUND: f64 = 1e-4;

#[test]
fn a_pure_delay_comes_back_in_band() {
    // IR: 0.5 at 3 samples, back to within the regularisation's bias.
    let l = layout(3);
    let mut ir = vec![0.0; 4];
    ir[3] = 0.5;
    let (velocity, loopback) = acquisition(&l, 1000, 700, &ir);
    let out = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
    assert_eq!(out.ir.len(), 512);
    let err = in_band_error(&out.ir, &ir, 4800);
    assert!(err < BIAS_BOUND, "in-band error {err:e}");
    // No drift, a whole-sample latency: both to rounding of the estimates (1e-3 ppm, 1e-4 sample).
    assert!(out.drift_ppm.abs() < 1e-3, "drift {}", out.drift_ppm);
    assert!((out.latency_samples - 1000.0).abs() < 1e-4, "latency {}", out.latency_samples);
    // Noise-free: the repetitions differ by rounding only, so the SNR is either unresolvable-high or huge.
    assert!(out.snr_db.is_none_or(|s| s > 150.0), "snr {:?}", out.snr_db);
}

#[test]
fn latency_zero_and_a_minimal_tail_work() {
    // Latency 0 (the grid starts before the recording: zeros) and the shortest tail the layout asks for.
    let l = layout(2);
    let c = cfg();
    let (velocity, loopback) = acquisition(&l, 0, c.ir_len + 2 * GUARD_SAMPLES, &[0.0, 1.0]);
    assert_eq!(velocity.len(), l.min_recording_samples(c.ir_len));
    let out = process_channel(&velocity, &loopback, &l, &c).unwrap();
    let err = in_band_error(&out.ir, &[0.0, 1.0], 4800);
    assert!(err < BIAS_BOUND, "in-band error {err:e}");
    assert!(out.latency_samples.abs() < 1e-4, "latency {}", out.latency_samples);
}

#[test]
fn one_repetition_has_no_snr_and_no_drift() {
    let l = layout(1);
    // The shortest recording the layout asks for.
    let (velocity, loopback) = acquisition(&l, 333, cfg().ir_len + 2 * GUARD_SAMPLES, &[0.0, 0.0, 0.25]);
    let out = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
    assert_eq!(out.snr_db, None);
    assert_eq!(out.drift_ppm, 0.0);
    assert!((out.latency_samples - 333.0).abs() < 1e-3, "latency {}", out.latency_samples);
    // Linear deconvolution, whose band limit acts on a longer FFT: the same bound holds up to the small
    // difference in how the skirts' ringing is truncated.
    let err = in_band_error(&out.ir, &[0.0, 0.0, 0.25], 4800);
    assert!(err < BIAS_BOUND, "in-band error {err:e}");
}

#[test]
fn shifted_sources_each_get_their_own_response_and_bad_shifts_are_refused() {
    // Two sources in one acquisition: the second plays the excitation circularly shifted by half the period
    // (2400 of 4800 samples), so its response lies 2400 samples later in the period. Cut at its shift, each
    // comes back as process_channel returns a source alone; at shift 0 the result is process_channel's, bit
    // for bit.
    let l = layout(3);
    let n = l.excitation.len();
    let (a, b) = (vec![0.0, 0.5, 0.0, -0.25], vec![0.0, 0.0, 0.3]);
    let (va, loopback) = acquisition(&l, 500, 700, &a);
    let mut shifted = l.excitation.clone();
    shifted.rotate_right(n / 2);
    let mut drive = vec![0.0; 500];
    drive.extend(shifted.iter().cycle().take(n * l.repetitions));
    drive.extend(std::iter::repeat_n(0.0, 700));
    let mut vb = convolve(&drive, &b).unwrap();
    vb.truncate(drive.len());
    let velocity: Vec<f64> = va.iter().zip(&vb).map(|(x, y)| x + y).collect();
    let prepared = PreparedLayout::new(&l, &cfg()).unwrap();
    let both = prepared.process_shifted(&velocity, &loopback, &[0, n / 2]).unwrap();
    assert_eq!(both.len(), 2);
    for (got, truth) in both.iter().zip([&a, &b]) {
        let err = in_band_error(&got.ir, truth, 4800);
        assert!(err < BIAS_BOUND, "in-band error {err:e}");
        assert!(got.snr_db.is_none_or(|s| s > 100.0), "noise-free: {:?}", got.snr_db);
    }
    let alone = prepared.process_channel(&va, &loopback).unwrap();
    assert_eq!(prepared.process_shifted(&va, &loopback, &[0]).unwrap(), vec![alone]);
    // No shift, a shift of a whole period or more, one repetition: refused, naming the shifts.
    for shifts in [vec![], vec![0, n]] {
        let err = prepared.process_shifted(&velocity, &loopback, &shifts).unwrap_err();
        assert!(matches!(err, DspError::InvalidParameter { name: "shifts", .. }), "{err}");
    }
    let one = PreparedLayout::new(&layout(1), &cfg()).unwrap();
    let (v1, l1) = acquisition(&layout(1), 100, 700, &a);
    assert!(matches!(one.process_shifted(&v1, &l1, &[0]), Err(DspError::InvalidParameter { name: "shifts", .. })));
}

#[test]
fn a_prepared_layout_gives_what_process_channel_gives() {
    // One preparation for several channels (latencies, responses, repetition counts): bit-identical results.
    for repetitions in [1, 3] {
        let l = layout(repetitions);
        let prepared = PreparedLayout::new(&l, &cfg()).unwrap();
        assert_eq!(prepared.layout(), &l);
        assert_eq!(prepared.config(), &cfg());
        for (latency, ir) in [(0, vec![0.0, 1.0]), (517, vec![0.5, 0.0, -0.25])] {
            let (velocity, loopback) = acquisition(&l, latency, 700, &ir);
            let out = prepared.process_channel(&velocity, &loopback).unwrap();
            assert_eq!(out, process_channel(&velocity, &loopback, &l, &cfg()).unwrap());
        }
    }
    // A bad layout or configuration is refused when preparing, a bad channel when processing.
    let none = RepetitionLayout { repetitions: 0, ..layout(2) };
    assert!(matches!(PreparedLayout::new(&none, &cfg()), Err(DspError::InvalidParameter { .. })));
    let bad_cfg = DeconvConfig { regularisation: -1.0, ..cfg() };
    assert!(matches!(PreparedLayout::new(&layout(2), &bad_cfg), Err(DspError::InvalidParameter { .. })));
    let prepared = PreparedLayout::new(&layout(2), &cfg()).unwrap();
    assert!(matches!(prepared.process_channel(&[1.0; 10], &[1.0; 9]), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(prepared.process_channel(&[], &[]), Err(DspError::Empty { .. })));
}

#[test]
fn refuses_bad_input() {
    let l = layout(2);
    let c = cfg();
    let (velocity, loopback) = acquisition(&l, 100, 700, &[1.0]);
    let run = |v: &[f64], lb: &[f64], lay: &RepetitionLayout, c: &DeconvConfig| process_channel(v, lb, lay, c);
    assert!(matches!(run(&velocity[1..], &loopback, &l, &c), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(run(&[], &[], &l, &c), Err(DspError::Empty { .. })));
    let mut nan = velocity.clone();
    nan[10] = f64::NAN;
    assert!(matches!(run(&nan, &loopback, &l, &c), Err(DspError::NonFinite { .. })));
    let none = RepetitionLayout { repetitions: 0, ..l.clone() };
    assert!(matches!(run(&velocity, &loopback, &none, &c), Err(DspError::InvalidParameter { .. })));
    let tiny = RepetitionLayout { excitation: vec![1.0], repetitions: 2 };
    assert!(matches!(run(&velocity, &loopback, &tiny, &c), Err(DspError::InvalidParameter { .. })));
    // A tail shorter than ir_len: the last response was not recorded.
    let cut = velocity.len() - 400;
    assert!(matches!(
        run(&velocity[..cut], &loopback[..cut], &l, &c),
        Err(DspError::InvalidParameter { name: "recording", .. })
    ));
    // An impulse response as long as the period cannot be told from its wrap-around.
    let long = DeconvConfig { ir_len: 4800, ..c };
    assert!(matches!(run(&velocity, &loopback, &l, &long), Err(DspError::InvalidParameter { name: "ir_len", .. })));
    // The recording started after the playback: the first copy is cut.
    assert!(matches!(
        run(&velocity[150..], &loopback[150..], &l, &c),
        Err(DspError::InvalidParameter { name: "recording", .. })
    ));
    let bad_cfg = DeconvConfig { sample_rate_hz: 0.0, ..c };
    assert!(run(&velocity, &loopback, &l, &bad_cfg).is_err());
}
