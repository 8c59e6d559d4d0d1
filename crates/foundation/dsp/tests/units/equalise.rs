#![allow(clippy::unwrap_used)]

use metaplate_dsp::error::DspError;
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::KirkebyConfig;

use metaplate_dsp::equalise::*;

const FS: f64 = 24_000.0;
const PRE: usize = 2048;

fn config() -> EqualiserConfig {
    EqualiserConfig {
        kirkeby: KirkebyConfig { response_delay_samples: PRE, ..KirkebyConfig::calibration_default() },
        fraction: 3.0,
        band_hz: (62.0, 625.0),
        tolerance_db: 0.25,
        max_designs: 8,
        standard: false,
    }
}

/// A response like an actuator on a plate: a falling broadband trend (a 70 Hz resonance, mass-controlled
/// above) plus lightly damped modes every few tens of hertz, time 0 at `PRE`.
fn plate_like(len: usize) -> Vec<f64> {
    let mut ir = vec![0.0; len];
    let modes = [(70.0, 0.15, 1.0), (113.0, 0.01, 0.4), (181.0, 0.008, 0.3), (262.0, 0.006, 0.2)];
    let extra: Vec<(f64, f64, f64)> = (0..12).map(|i| (300.0 + 27.3 * i as f64, 0.005, 0.08)).collect();
    for (f, zeta, a) in modes.iter().chain(&extra) {
        let w = 2.0 * std::f64::consts::PI * f;
        for (i, v) in ir[PRE..].iter_mut().enumerate() {
            let t = i as f64 / FS;
            *v += a * (-zeta * w * t).exp() * (w * t).sin();
        }
    }
    ir
}

#[test]
fn a_plate_like_response_is_flattened_within_the_tolerance_by_refinement() {
    let ir = plate_like(8192);
    let once = design_equaliser(&ir, &EqualiserConfig { max_designs: 1, ..config() }).unwrap();
    let refined = design_equaliser(&ir, &config()).unwrap();
    assert_eq!(once.designs, 1);
    // One design leaves the smoothed product off by more than the tolerance; refinement brings it within.
    assert!(once.predicted_deviation_db() > 0.5, "{:?}", once.predicted_range_db);
    assert!(refined.predicted_deviation_db() <= 0.25, "{:?} after {}", refined.predicted_range_db, refined.designs);
    assert!(refined.designs > 1);
    // Check the prediction independently: the verification (the response through the taps, cut to its
    // length about time 0), smoothed, over the band. The same computation on another FFT grid: to rounding.
    let (worst, _) = verified(&ir, &refined);
    assert!((worst - refined.predicted_deviation_db()).abs() < 1e-6, "independent check: {worst:.2} dB");
}

/// A response like an actuator's at its own magnet on the plate: a broad 70 Hz suspension resonance
/// (mass-controlled above) plus lightly damped plate modes from 75 to 900 Hz about a tenth of an octave apart,
/// each with a positive residue (a cosine onset), so anti-resonances lie between them as at a driving point.
/// Time 0 at `PRE`.
fn driving_point(len: usize) -> Vec<f64> {
    let mut ir = vec![0.0; len];
    let suspension = (70.0, 0.15, 1.0);
    let plate: Vec<(f64, f64, f64)> = (0..36)
        .map(|i| (75.0 * 2f64.powf(i as f64 / 10.0), 0.004 + 0.002 * (i % 3) as f64, 0.25 + 0.15 * (i % 4) as f64))
        .collect();
    for (f, zeta, a) in std::iter::once(&suspension).chain(&plate) {
        let w = 2.0 * std::f64::consts::PI * f;
        for (i, v) in ir[PRE..].iter_mut().enumerate() {
            let t = i as f64 / FS;
            *v += a * (-zeta * w * t).exp() * (w * t).cos();
        }
    }
    ir
}

/// The verification a measurement through `eq`'s taps gives (the response through them, advanced by the
/// modelling delay, cut to the response's length), judged independently of the design: its deviation on the
/// project's smoothing and on the standard one, dB.
fn verified(ir: &[f64], eq: &Equaliser) -> (f64, f64) {
    let through = metaplate_dsp::conv::convolve(ir, &eq.filter.taps).unwrap();
    let delay = eq.filter.modelling_delay_samples;
    let v = &through[delay..delay + ir.len()];
    let own = metaplate_dsp::smooth::smoothed_levels_db(v, FS, 3.0, (62.0, 625.0)).unwrap();
    let standard = metaplate_dsp::smooth::standard_levels_db(v, FS, 3.0, (62.0, 625.0)).unwrap();
    (deviation(range_about_median(&own)), deviation(range_about_median(&standard)))
}

fn calibration() -> EqualiserConfig {
    EqualiserConfig::calibration(KirkebyConfig { response_delay_samples: PRE, ..KirkebyConfig::calibration_default() })
}

#[test]
fn narrow_modes_are_flattened_within_1_db_on_both_smoothings_where_one_alone_is_not() {
    let ir = driving_point(8192);
    let both = design_equaliser(&ir, &calibration()).unwrap();
    let own_only = design_equaliser(&ir, &EqualiserConfig { standard: false, ..calibration() }).unwrap();
    let (own, standard) = verified(&ir, &own_only);
    eprintln!("own smoothing alone: {own:.2} / {standard:.2} dB after {} designs", own_only.designs);
    // Flattening the project's smoothing alone leaves the standard one beyond the requirement: the magnitude
    // average over the modes reads up to 2 dB below the power average, unevenly.
    assert!(own_only.predicted_standard_range_db.is_none());
    assert!(own <= 0.3 && standard > 1.0, "{own:.2} / {standard:.2} dB");
    let (own, standard) = verified(&ir, &both);
    eprintln!(
        "both: {own:.2} / {standard:.2} dB after {} designs, predicted {:?} / {:?}",
        both.designs, both.predicted_range_db, both.predicted_standard_range_db
    );
    if std::env::var("EQ_DEBUG").is_ok() {
        for eq in [&own_only, &both] {
            let through = metaplate_dsp::conv::convolve(&ir, &eq.filter.taps).unwrap();
            let v = &through[480..480 + ir.len()];
            let own = metaplate_dsp::smooth::smoothed_levels_db(v, FS, 3.0, (62.0, 625.0)).unwrap();
            let st = metaplate_dsp::smooth::standard_levels_db(v, FS, 3.0, (40.0, 800.0)).unwrap();
            for (f, l) in own.iter().step_by(8) {
                let s = st.iter().min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs())).unwrap().1;
                eprintln!("{f:7.1} {l:7.2} {s:7.2} {:6.2}", s - l);
            }
        }
    }
    // Aiming between them holds both within the requirement, +/-1 dB.
    assert!(own <= 1.0 && standard <= 1.0, "{own:.2} / {standard:.2} dB");
    // The prediction is this same computation on the design's grid: equal to rounding.
    assert!((both.predicted_deviation_db() - own).abs() < 1e-6, "{both:?}");
    assert!((both.predicted_standard_deviation_db().unwrap() - standard).abs() < 1e-6, "{both:?}");
}

#[test]
fn what_the_standard_smoothing_cannot_see_measured_is_refused_or_reported() {
    let ir = driving_point(8192);
    // A Kirkeby band ending at 625 Hz: the standard window at 625 Hz averages up to 701.5 Hz, where the filter
    // may not invert. Refused, naming the band.
    let narrow = EqualiserConfig {
        kirkeby: KirkebyConfig { response_delay_samples: PRE, ..KirkebyConfig::calibration_default() },
        ..calibration()
    };
    let err = design_equaliser(&ir, &narrow).unwrap_err();
    assert!(matches!(err, DspError::InvalidParameter { name: "kirkeby.profile.band", .. }), "{err}");
    // A response measured only up to 625 Hz (band-limited, as a sweep ending there leaves it) with the wide
    // Kirkeby band: nothing above 625 Hz to lift, so the standard smoothing falls at the top whatever the
    // filter does. The design reports it: its best prediction, beyond 1 dB, after every design it was allowed.
    let n = fft::fast_len(2 * ir.len()).unwrap();
    let band = metaplate_dsp::band::BandLimit::new(50.0, 625.0, 20.0, 20.0).unwrap();
    let mut spectrum = fft::forward(&ir, n).unwrap();
    spectrum.iter_mut().zip(band.bin_gains(n, FS)).for_each(|(s, g)| *s *= g);
    let limited = fft::inverse(&spectrum, n).unwrap()[..ir.len()].to_vec();
    let eq = design_equaliser(&limited, &calibration()).unwrap();
    let standard = eq.predicted_standard_deviation_db().unwrap();
    assert!(
        standard > 1.0 && eq.designs == calibration().max_designs,
        "{:?} / {:?} after {}",
        eq.predicted_range_db,
        eq.predicted_standard_range_db,
        eq.designs
    );
    assert!((verified(&limited, &eq).1 - standard).abs() < 1e-6);
}

#[test]
fn a_flat_response_needs_one_design() {
    let mut ir = vec![0.0; 8192];
    ir[PRE] = 0.01;
    let eq = design_equaliser(&ir, &config()).unwrap();
    assert_eq!(eq.designs, 1);
    assert!(eq.predicted_deviation_db() < 0.25, "{:?}", eq.predicted_range_db);
}

#[test]
fn bad_input_is_refused() {
    let ir = plate_like(8192);
    for bad in [
        EqualiserConfig { tolerance_db: 0.0, ..config() },
        EqualiserConfig { tolerance_db: f64::NAN, ..config() },
        EqualiserConfig { max_designs: 0, ..config() },
        EqualiserConfig { max_designs: 65, ..config() },
        EqualiserConfig { fraction: 0.5, ..config() },
        EqualiserConfig { band_hz: (625.0, 62.0), ..config() },
        EqualiserConfig { band_hz: (100.0, 100.001), ..config() },
    ] {
        assert!(matches!(design_equaliser(&ir, &bad), Err(DspError::InvalidParameter { .. })), "{bad:?}");
    }
    assert!(design_equaliser(&ir[..PRE], &config()).is_err(), "time 0 past the end");
    assert!(design_equaliser(&vec![0.0; 8192], &config()).is_err(), "no power to invert");
    let mut nan = ir.clone();
    nan[3000] = f64::NAN;
    assert!(matches!(design_equaliser(&nan, &config()), Err(DspError::NonFinite { .. })));
}
