//! Excitation protocols on a synthetic linear "plate": 8 actuators with known decaying responses, white noise at the
//! sensor, the player and the recorder on one clock with a latency. Sequential, Hadamard and interleaved protocols
//! must recover every response, and the Hadamard protocol must buy its speed without losing accuracy.
#![allow(clippy::unwrap_used)]

use metaplate_core::rng::SplitMix64;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::conv::convolve;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme, hadamard};
use metaplate_dsp::sweep::SweepSpec;

const FS_HZ: f64 = 4000.0;
const ACTUATORS: usize = 8;
const IR_LEN: usize = 400; // 0.1 s
const LATENCY: usize = 37;

fn cfg() -> DeconvConfig {
    DeconvConfig {
        sample_rate_hz: FS_HZ,
        ir_len: IR_LEN,
        pre_samples: 0,
        band: Some(BandLimit { lo_hz: 62.0, hi_hz: 625.0, lo_transition_hz: 20.0, hi_transition_hz: 50.0 }),
        regularisation: 1e-3,
    }
}

fn sweep(duration_s: f64) -> SweepSpec {
    SweepSpec { duration_s, sample_rate_hz: FS_HZ, ..SweepSpec::default() }
}

/// Actuator k's response: a few decaying modes, different per actuator, well inside 0.1 s (decay time 10 ms).
fn responses() -> Vec<Vec<f64>> {
    let mut rng = SplitMix64::new(7, 0);
    (0..ACTUATORS)
        .map(|_| {
            let modes: Vec<(f64, f64, f64)> = (0..4)
                .map(|_| (80.0 + 500.0 * rng.uniform(), rng.uniform() * std::f64::consts::TAU, 0.5 + rng.uniform()))
                .collect();
            (0..IR_LEN / 2)
                .map(|n| {
                    let t = n as f64 / FS_HZ;
                    modes.iter().map(|(f, p, a)| a * (std::f64::consts::TAU * f * t + p).sin()).sum::<f64>()
                        * (-t / 0.01).exp()
                })
                .collect()
        })
        .collect()
}

/// Gaussian noise of standard deviation `sigma`.
fn noise(rng: &mut SplitMix64, n: usize, sigma: f64) -> Vec<f64> {
    (0..n).map(|_| sigma * rng.normal()).collect()
}

/// Plays every shot of `protocol` through the linear plate and records velocity and loopback.
fn record(protocol: &ExcitationProtocol, noise_sigma: f64, seed: u64) -> Vec<(Vec<f64>, Vec<f64>)> {
    record_with(protocol, noise_sigma, seed, &[1.0; ACTUATORS], |x| x)
}

/// As [`record`], with actuator k's response scaled by `gains[k]` and each drive sample passed through `coil` (a
/// static nonlinearity, as the voice coils' Hammerstein model) before the plate.
fn record_with(
    protocol: &ExcitationProtocol,
    noise_sigma: f64,
    seed: u64,
    gains: &[f64],
    coil: fn(f64) -> f64,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let g = responses();
    let mut rng = SplitMix64::new(seed, 0);
    let len = LATENCY + protocol.shot_len_samples(ACTUATORS, FS_HZ) + 2 * IR_LEN;
    protocol
        .shots(ACTUATORS)
        .unwrap()
        .iter()
        .map(|shot| {
            let mut velocity = noise(&mut rng, len, noise_sigma);
            for (k, g_k) in g.iter().enumerate() {
                if let Some(drive) = protocol.drive(shot, k, FS_HZ).unwrap() {
                    let drive: Vec<f64> = drive.iter().map(|&x| coil(x)).collect();
                    let y = convolve(&drive, g_k).unwrap();
                    for (v, y) in velocity[LATENCY..].iter_mut().zip(&y) {
                        *v += gains[k] * y;
                    }
                }
            }
            let mut loopback = vec![0.0; len];
            let reference = protocol.reference(FS_HZ).unwrap();
            loopback[LATENCY..LATENCY + reference.len()].copy_from_slice(&reference);
            (velocity, loopback)
        })
        .collect()
}

fn decode(protocol: &ExcitationProtocol, recordings: &[(Vec<f64>, Vec<f64>)]) -> Vec<Vec<f64>> {
    decode_with(protocol, recordings, &cfg())
}

fn decode_with(
    protocol: &ExcitationProtocol,
    recordings: &[(Vec<f64>, Vec<f64>)],
    cfg: &DeconvConfig,
) -> Vec<Vec<f64>> {
    let pairs: Vec<(&[f64], &[f64])> = recordings.iter().map(|(v, l)| (v.as_slice(), l.as_slice())).collect();
    protocol.decode(ACTUATORS, &pairs, cfg).unwrap().into_iter().map(|r| r.ir).collect()
}

/// Error energy of `got` against `truth`, relative to the truth's energy, summed over actuators, dB.
fn error_db(got: &[Vec<f64>], truth: &[Vec<f64>]) -> f64 {
    let (mut err, mut sig) = (0.0, 0.0);
    for (g, t) in got.iter().zip(truth) {
        err += g.iter().zip(t).map(|(a, b)| (a - b) * (a - b)).sum::<f64>();
        sig += t.iter().map(|x| x * x).sum::<f64>();
    }
    10.0 * (err / sig).log10()
}

#[test]
fn hadamard_matrix_is_orthogonal() {
    for order in [1, 2, 4, 8, 64] {
        for a in 0..order {
            for b in 0..order {
                let dot: f64 = (0..order).map(|s| hadamard(s, a) * hadamard(s, b)).sum();
                assert_eq!(dot, if a == b { order as f64 } else { 0.0 }, "order {order}, columns {a} {b}");
            }
        }
    }
}

#[test]
fn noiseless_protocols_agree_with_the_sequential_one() {
    let reference = decode(
        &ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2),
        &record(&ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2), 0.0, 1),
    );
    // Superposition is exact for a linear plate, so only rounding separates the Hadamard decode from the sequential
    // one: -200 dB would be machine precision; -100 dB leaves room for the FFTs' rounding over 8 shots.
    let hadamard = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 2);
    let e = error_db(&decode(&hadamard, &record(&hadamard, 0.0, 1)), &reference);
    assert!(e < -100.0, "Hadamard vs sequential: {e:.1} dB");
    // The interleaved protocol deconvolves one long exponential sweep linearly (not periodically), against a
    // periodic linear-sweep reference: both are the same band-limited response up to the regularisation bias and
    // the window's truncation of the band-limit ringing (-51 to -56 dB per actuator here; -30 dB would mean a
    // misplaced slot, which costs -5 dB per sample at 4 kHz).
    let exp = sweep(1.0).as_exponential();
    let interleaved = ExcitationProtocol::new(
        "test",
        Scheme::Interleaved { slot_s: 0.1 + exp.exp_rate_s().unwrap() * 3f64.ln() + 0.01 },
        exp,
        1,
    );
    // An exponential sweep's power falls with frequency, so it needs a lower regularisation (see
    // `DeconvConfig::paper`).
    let exp_cfg = DeconvConfig { regularisation: 1e-5, ..cfg() };
    let e = error_db(&decode_with(&interleaved, &record(&interleaved, 0.0, 1), &exp_cfg), &reference);
    assert!(e < -30.0, "interleaved vs sequential: {e:.1} dB");
}

#[test]
fn hadamard_is_as_accurate_in_an_eighth_of_the_time() {
    // Same noise. Sequential: 8 shots of 4 periods. Hadamard: 8 shots of 4 periods too (the same time) must be about
    // 9 dB (8x in noise energy) more accurate; and in an eighth of the time (periods of 1/8 the length would not
    // hold the response, so: 8 shots of 4 periods of 0.25 s vs 8 shots of 4 periods of 2 s) equally accurate.
    let truth = decode(
        &ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2),
        &record(&ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2), 0.0, 1),
    );
    let sigma = 0.05;
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 4);
    let had = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 4);
    let e_seq = error_db(&decode(&seq, &record(&seq, sigma, 2)), &truth);
    let e_had = error_db(&decode(&had, &record(&had, sigma, 3)), &truth);
    // 10 log10(8) = 9.0 dB expected; the error estimate from one noise draw over 8 x 400 samples is good to about
    // +/-1 dB, so 7 to 11 dB.
    let gain = e_seq - e_had;
    assert!((7.0..11.0).contains(&gain), "Hadamard gain {gain:.1} dB (sequential {e_seq:.1}, Hadamard {e_had:.1})");
    let fast = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(0.25), 4);
    let slow = ExcitationProtocol::new("test", Scheme::Sequential, sweep(2.0), 4);
    let (t_fast, t_slow) = (fast.time_per_point_s(ACTUATORS, 0.1), slow.time_per_point_s(ACTUATORS, 0.1));
    let e_fast = error_db(&decode(&fast, &record(&fast, sigma, 4)), &truth);
    let e_slow = error_db(&decode(&slow, &record(&slow, sigma, 5)), &truth);
    assert!(t_slow / t_fast > 6.0, "time ratio {:.2}", t_slow / t_fast);
    // Equal energy per actuator, so equal noise: within the +/-1.5 dB of two independent draws.
    assert!((e_fast - e_slow).abs() < 1.5, "fast Hadamard {e_fast:.1} dB vs slow sequential {e_slow:.1} dB");
}

#[test]
fn hadamard_snr_reflects_the_averaging() {
    let had = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 4);
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 4);
    let snr = |p: &ExcitationProtocol, seed| {
        let recordings = record(p, 0.05, seed);
        let pairs: Vec<(&[f64], &[f64])> = recordings.iter().map(|(v, l)| (v.as_slice(), l.as_slice())).collect();
        let results = p.decode(ACTUATORS, &pairs, &cfg()).unwrap();
        results.iter().map(|r| r.snr_db.unwrap()).sum::<f64>() / ACTUATORS as f64
    };
    // The SNR estimates are rough (spread of 4 repetitions, and an energy ratio through the decode): the Hadamard
    // average must come out higher by the 9 dB of averaging within +/-4 dB.
    let gain = snr(&had, 6) - snr(&seq, 7);
    assert!((5.0..13.0).contains(&gain), "SNR gain {gain:.1} dB");
}

#[test]
fn protocols_refuse_what_they_cannot_measure() {
    let exp = sweep(1.0).as_exponential();
    let short_slot = ExcitationProtocol::new("test", Scheme::Interleaved { slot_s: 0.2 }, exp, 1);
    let err = short_slot.validate(ACTUATORS, 0.1).unwrap_err().to_string();
    assert!(err.contains("slot_s") && err.contains("third harmonic"), "{err}");
    let linear = ExcitationProtocol::new("test", Scheme::Interleaved { slot_s: 5.0 }, sweep(1.0), 1);
    assert!(linear.validate(ACTUATORS, 0.1).unwrap_err().to_string().contains("exponential"));
    let none = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 0);
    assert!(none.validate(ACTUATORS, 0.1).is_err());
    assert!(ExcitationProtocol::paper().validate(0, 0.5).is_err());
    assert!(ExcitationProtocol::paper().validate(65, 0.5).is_err());
    // Wrong number of recordings.
    let recordings = record(&ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2), 0.0, 1);
    let pairs: Vec<(&[f64], &[f64])> = recordings.iter().take(7).map(|(v, l)| (v.as_slice(), l.as_slice())).collect();
    let err = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2)
        .decode(ACTUATORS, &pairs, &cfg())
        .unwrap_err();
    assert!(err.to_string().contains("recordings and shots"), "{err}");
}

#[test]
fn extremes_one_actuator_and_one_repetition() {
    // One actuator: a Hadamard protocol of order 1 is the sequential one.
    let one = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 1);
    assert_eq!(one.shots(1).unwrap().len(), 1);
    // Paper timing: 8 actuators x 5 x 3 s + 0.5 s ring-out each = 124 s per point.
    assert!((ExcitationProtocol::paper().time_per_point_s(8, 0.5) - 124.0).abs() < 1e-9);
    // Non-power-of-two actuator counts round the Hadamard order up.
    assert_eq!(ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 1).shots(5).unwrap().len(), 8);
}

#[test]
fn extremes_short_sweeps_and_a_response_longer_than_the_period() {
    // A period shorter than the response cannot be deconvolved periodically: refused, naming the period.
    let short = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(0.05), 2);
    let err = short.validate(ACTUATORS, 0.1).unwrap_err().to_string();
    assert!(err.contains("ir_len_s") && err.contains("period"), "{err}");
    let pairs: Vec<(&[f64], &[f64])> = Vec::new();
    assert!(short.decode(ACTUATORS, &pairs, &cfg()).is_err());
    // The shortest sweep that holds the 0.1 s response plus the pipeline's guard (0.15 s) still recovers every
    // response without noise: -60 dB leaves room for the band limit's truncation in a period this short.
    let shortest = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(0.15), 2);
    let truth = decode(
        &ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2),
        &record(&ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2), 0.0, 1),
    );
    let e = error_db(&decode(&shortest, &record(&shortest, 0.0, 1)), &truth);
    assert!(e < -40.0, "0.15 s Hadamard sweeps: {e:.1} dB");
}

#[test]
fn extremes_one_repetition_decodes_without_an_snr() {
    let truth = decode(
        &ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2),
        &record(&ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2), 0.0, 1),
    );
    let one = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 1);
    let recordings = record(&one, 0.0, 1);
    let pairs: Vec<(&[f64], &[f64])> = recordings.iter().map(|(v, l)| (v.as_slice(), l.as_slice())).collect();
    let results = one.decode(ACTUATORS, &pairs, &cfg()).unwrap();
    // One period: linear deconvolution, the same responses (up to its different truncation: -40 dB), no SNR.
    let irs: Vec<Vec<f64>> = results.iter().map(|r| r.ir.clone()).collect();
    let e = error_db(&irs, &truth);
    assert!(e < -40.0, "one repetition: {e:.1} dB");
    assert!(results.iter().all(|r| r.snr_db.is_none()));
}

#[test]
fn extremes_40_db_spread_between_actuators_does_not_leak() {
    // Actuator 3 is 40 dB quieter than the others. Superposition is exact, so the Hadamard decode separates it as
    // well as the sequential protocol does: its own error stays at rounding level (-100 dB as above) rather than
    // being swamped by the loud ones' energy (which would read about +40 dB).
    let mut gains = [1.0; ACTUATORS];
    gains[3] = 0.01;
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2);
    let had = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 2);
    let a = decode(&seq, &record_with(&seq, 0.0, 1, &gains, |x| x));
    let b = decode(&had, &record_with(&had, 0.0, 1, &gains, |x| x));
    let e = error_db(&b[3..4], &a[3..4]);
    assert!(e < -100.0, "quiet actuator: {e:.1} dB");
}

#[test]
fn extremes_strong_nonlinearity_odd_stays_with_its_actuator_even_leaves_the_others() {
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2);
    let had = ExcitationProtocol::new("test", Scheme::Hadamard, sweep(1.0), 2);
    // A 30 % cubic flips sign with the drive, so each actuator's distortion decodes with it, exactly as in the
    // sequential protocol: the two decodes agree to rounding (-100 dB).
    let cubic = |x: f64| x + 0.3 * x * x * x;
    let a = decode(&seq, &record_with(&seq, 0.0, 1, &[1.0; ACTUATORS], cubic));
    let b = decode(&had, &record_with(&had, 0.0, 1, &[1.0; ACTUATORS], cubic));
    let e = error_db(&b, &a);
    assert!(e < -100.0, "cubic: Hadamard vs sequential {e:.1} dB");
    // A 30 % quadratic does not flip with the sign: it leaves actuators 1..7 (their columns sum to zero over the
    // shots), which come out far cleaner than sequentially; it stays in the all-ones column, actuator 0, which must
    // be no worse than sequentially by more than 10 dB (measured: -56 dB Hadamard, -40 dB sequential: on a linear
    // sweep the squared sweep's content mostly falls outside the band and the period's alignment).
    let quad = |x: f64| x + 0.3 * x * x;
    let linear = decode(&seq, &record(&seq, 0.0, 1));
    let a = decode(&seq, &record_with(&seq, 0.0, 1, &[1.0; ACTUATORS], quad));
    let b = decode(&had, &record_with(&had, 0.0, 1, &[1.0; ACTUATORS], quad));
    let (seq_rest, had_rest) = (error_db(&a[1..], &linear[1..]), error_db(&b[1..], &linear[1..]));
    let (seq_0, had_0) = (error_db(&a[..1], &linear[..1]), error_db(&b[..1], &linear[..1]));
    assert!(had_rest < seq_rest - 20.0, "actuators 1..7: Hadamard {had_rest:.1} dB, sequential {seq_rest:.1} dB");
    assert!(had_0 < seq_0 + 10.0, "actuator 0: Hadamard {had_0:.1} dB, sequential {seq_0:.1} dB");
}

/// All actuators in one shot, circularly shifted by a slot of `duration_s / 8` each (`staggered:DxR`).
fn staggered(duration_s: f64, repetitions: usize) -> ExcitationProtocol {
    ExcitationProtocol::new("test", Scheme::Staggered, sweep(duration_s), repetitions)
}

/// The 0.1 s responses' in-band error against `truth` per actuator, measured, and the row's own estimate, dB.
fn measured_and_estimated(results: &[metaplate_dsp::pipeline::ChannelResult], truth: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let band = metaplate_dsp::accuracy::ERROR_BAND_HZ;
    results
        .iter()
        .zip(truth)
        .map(|(r, t)| {
            let diff: Vec<f64> = r.ir.iter().zip(t).map(|(a, b)| a - b).collect();
            let measured = metaplate_dsp::accuracy::band_energy(&diff, band, FS_HZ).unwrap()
                / metaplate_dsp::accuracy::band_energy(t, band, FS_HZ).unwrap();
            (10.0 * measured.log10(), r.estimated_error_db(FS_HZ).unwrap())
        })
        .collect()
}

/// The harness's deconvolution with a regularisation of 1e-6: its bias is then below -100 dB for every sweep here,
/// whereas at 1e-3 a 4.8 s and a 1 s sweep differ by -52 dB in it (their Fresnel ripples differ), which would hide
/// what the comparisons below are about.
fn unbiased() -> DeconvConfig {
    DeconvConfig { regularisation: 1e-6, ..cfg() }
}

#[test]
fn staggered_sweeps_recover_every_response_from_one_shot() {
    // Noise-free, a linear plate: every actuator's response sits in its own 0.6 s slot of the 4.8 s period (the
    // responses last 50 ms), so the one shot decodes to the sequential protocol's responses up to rounding and the
    // regularisation's bias (measured -104 dB).
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2);
    let reference = decode_with(&seq, &record(&seq, 0.0, 1), &unbiased());
    let one = staggered(4.8, 2);
    assert_eq!(one.shots(ACTUATORS).unwrap().len(), 1);
    let e = error_db(&decode_with(&one, &record(&one, 0.0, 1), &unbiased()), &reference);
    assert!(e < -100.0, "staggered vs sequential: {e:.1} dB");
}

#[test]
fn staggered_sweeps_are_as_accurate_in_an_eighth_of_the_time() {
    // Equal sweep per actuator: staggered 4.8 s x 2 (9.6 s each, in one shot) against sequential 2.4 s x 4 (9.6 s
    // each, in 8 shots). Equal noise within +/-1.5 dB (the mean of 3 draws each), in 8 times less playing.
    let reference = ExcitationProtocol::new("test", Scheme::Sequential, sweep(1.0), 2);
    let truth = decode_with(&reference, &record(&reference, 0.0, 1), &unbiased());
    let sigma = 0.05;
    let one = staggered(4.8, 2);
    let seq = ExcitationProtocol::new("test", Scheme::Sequential, sweep(2.4), 4);
    let mean_error = |p: &ExcitationProtocol, seed: u64| {
        let draws: f64 = (0..3)
            .map(|d| 10f64.powf(error_db(&decode_with(p, &record(p, sigma, seed + d), &unbiased()), &truth) / 10.0))
            .sum();
        10.0 * (draws / 3.0).log10()
    };
    let (e_one, e_seq) = (mean_error(&one, 40), mean_error(&seq, 50));
    assert!((e_one - e_seq).abs() < 1.5, "staggered {e_one:.1} dB vs sequential {e_seq:.1} dB");
    let (t_one, t_seq) = (one.time_per_point_s(ACTUATORS, 0.1), seq.time_per_point_s(ACTUATORS, 0.1));
    assert!((t_one - 9.7).abs() < 1e-9 && (t_seq - 77.6).abs() < 1e-9, "{t_one} s vs {t_seq} s");
    // Each row's estimate (the period's noise, of which each response keeps its window) predicts its error: within
    // 2 dB on one draw (the noise over the ~90 bins of a 0.1 s response in the band scatters by about 1 dB).
    let recordings = record(&one, sigma, 60);
    let pairs: Vec<(&[f64], &[f64])> = recordings.iter().map(|(v, l)| (v.as_slice(), l.as_slice())).collect();
    let results = one.decode(ACTUATORS, &pairs, &unbiased()).unwrap();
    for (k, (measured, estimated)) in measured_and_estimated(&results, &truth).into_iter().enumerate() {
        assert!(
            (measured - estimated).abs() < 2.0,
            "actuator {k}: measured {measured:.1} dB, estimated {estimated:.1}"
        );
        assert!(results[k].snr_db.is_some(), "actuator {k} has an SNR");
    }
}

#[test]
fn staggered_sweeps_refuse_slots_too_short_and_single_periods() {
    // 8 slots of 0.5 s: shorter than the 0.6 s a slot needs (the scan's 0.5 s responses and their precursor).
    let err = staggered(4.0, 2).validate(ACTUATORS, 0.1).unwrap_err().to_string();
    assert!(err.contains("slot"), "{err}");
    // Fewer actuators, longer slots: the same period holds 4.
    assert!(staggered(4.0, 2).validate(4, 0.5).is_ok());
    let err = staggered(4.8, 1).validate(ACTUATORS, 0.1).unwrap_err().to_string();
    assert!(err.contains("2 periods"), "{err}");
    assert!(metaplate_dsp::excitation::parse("staggered:5x1").unwrap_err().to_string().contains("2 periods"));
    let p = metaplate_dsp::excitation::parse("staggered:5x3").unwrap();
    assert_eq!((p.scheme, p.repetitions()), (Scheme::Staggered, 3));
    // One shot holding every actuator: no per-shot decode.
    let decoder = p.decoder(8, &DeconvConfig { sample_rate_hz: 24_000.0, ..p.deconv }).unwrap();
    assert!(decoder.decode_shot(&[0.0; 10], &[0.0; 10]).is_err());
}
