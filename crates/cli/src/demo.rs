//! `metaplate demo`: the main job, on the built-in simulated plates, with no hardware and no arguments.
//!
//! Today (before the drivers, the mock lab and the recipes exist) it runs what the suite has:
//! 1. both built-in plates: dispersion with the paper's k-space method, against the paper's measured wavelengths;
//! 2. both plates: ground-truth Green's functions written as datasets (a reduced grid by default, `--full` for the
//!    paper's), readable by polars and pyarrow;
//! 3. the measurement chain for one grid point and all 8 actuators of the metamaterial plate: Kirkeby calibration of
//!    each voice coil, then the paper's protocol (5 x 3 s linear sweep, compensated) through the actuator (with its
//!    nonlinearity), the plate, LDV noise, 16-bit quantisation, latency and 50 ppm of clock drift between the audio
//!    interface and the DAQ, and back through the per-point pipeline (drift correction, coherent averaging,
//!    reference deconvolution). The signal path here is a stand-in for the mock lab, which replaces it once the
//!    drivers land; the processing is the real library code a scan uses.
//!
//! It prints a paper-against-suite table and writes `summary.json` in the output directory.

use std::fs;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_core::scene::Scene;
use metaplate_dsp::deconv::{DeconvConfig, deconvolve};
use metaplate_dsp::drift::Interpolator;
use metaplate_dsp::kirkeby::{self, KirkebyConfig};
use metaplate_dsp::pipeline::{ChannelResult, RepetitionLayout, process_channel};
use metaplate_dsp::sweep::SweepSpec;
use metaplate_dsp::{conv, fft};
use metaplate_plate::actuator::VoiceCoil;
use metaplate_plate::{GreensRequest, ModelOptions};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde_json::{Value, json};

use crate::{progress, simulate, wav};

/// Arguments of `metaplate demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Output directory (created; an earlier demo's datasets in it are replaced).
    #[arg(long, default_value = "metaplate-demo")]
    out: PathBuf,
    /// Use the paper's full 49 x 25 grid for the ground truth instead of a 13 x 7 subset.
    #[arg(long)]
    full: bool,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Frequencies of the dispersion table, Hz: the paper's two measured points and the band between.
const DISPERSION_FREQS_HZ: [f64; 6] = [75.0, 150.0, 250.0, 400.0, 500.0, 600.0];

/// Clock offsets of the stand-in measurement, ppm: the audio interface slow, the DAQ fast, 50 ppm apart.
const AUDIO_PPM: f64 = -30.0;
const DAQ_PPM: f64 = 20.0;
/// Latency from the first played sample to its arrival at the DAQ, samples (a fraction, as in the lab).
const LATENCY_SAMPLES: f64 = 157.3;

/// Runs the demo.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let started = std::time::Instant::now();
    let options = ModelOptions::default();
    let mut plates = serde_json::Map::new();
    for name in ["metamaterial", "homogeneous"] {
        let scene = Scene::builtin(name)?;
        eprintln!("[{name}] dispersion at {} frequencies", DISPERSION_FREQS_HZ.len());
        let dispersion = simulate::dispersion(&scene, &options, &DISPERSION_FREQS_HZ)?;
        let grid = if args.full { None } else { Some((13, 7)) };
        let points = simulate::select_points(&scene, grid)?;
        eprintln!(
            "[{name}] ground-truth Green's functions: {} points x {} actuators",
            points.len(),
            scene.actuators.len()
        );
        let request = GreensRequest {
            points,
            actuators: (0..scene.actuators.len()).collect(),
            band_hz: (50.0, 700.0),
            duration_s: 0.5,
            sample_rate_hz: scene.daq.sample_rate_hz,
        };
        let dir = args.out.join(name).join("ground-truth");
        let ground_truth = simulate::write_ground_truth(&scene, &options, &request, &dir, true, None)?;
        plates.insert(name.into(), json!({ "dispersion": dispersion, "ground_truth": ground_truth }));
    }
    let scene = Scene::builtin("metamaterial")?;
    eprintln!("[metamaterial] measurement chain at the centre point, 8 actuators");
    let chain = measurement_chain(&scene, &options, args)?;
    let summary = json!({
        "plates": plates,
        "measurement_chain": chain,
        "wall_time_s": started.elapsed().as_secs_f64(),
    });
    print_table(&summary);
    let path = args.out.join("summary.json");
    fs::write(&path, serde_json::to_string_pretty(&summary)?).with_context(|| format!("writing {}", path.display()))?;
    println!("\nwrote {} and the datasets under {}", path.display(), args.out.display());
    Ok(())
}

/// The stand-in measurement of one grid point (see the module documentation).
fn measurement_chain(scene: &Scene, options: &ModelOptions, args: &DemoArgs) -> anyhow::Result<Value> {
    let fs_hz = scene.daq.sample_rate_hz;
    let centre = scene.grid.index(scene.grid.nx / 2, scene.grid.ny / 2);
    let actuators: Vec<usize> = (0..scene.actuators.len()).collect();
    let request = GreensRequest {
        points: vec![centre],
        actuators: actuators.clone(),
        band_hz: (50.0, 700.0),
        duration_s: 0.5,
        sample_rate_hz: fs_hz,
    };
    let greens = metaplate_plate::greens_functions(scene, options, &request, None)?;
    let coils = VoiceCoil::for_scene(scene, fs_hz)?;
    let excitation = SweepSpec { amplitude: 0.5, ..SweepSpec::default() }.generate()?;
    let layout = RepetitionLayout { excitation: excitation.clone(), repetitions: 5 };
    let cfg = DeconvConfig::paper();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
    let bar = progress::bar(actuators.len() as u64, "actuators");
    let mut rows = Vec::new();
    let mut measured_irs = Vec::new();
    for (k, coil) in coils.iter().enumerate() {
        let g = greens.ir(0, k).context("internal: missing Green's function")?;
        let calibration = calibrate(coil)?;
        // The actuator channel plays the compensated excitation; the loopback channel plays it uncompensated, so
        // dividing by the loopback yields the compensated Green's function (Kirkeby filter x coil x plate).
        let played = repeat(&excitation, layout.repetitions, fs_hz);
        let drive = calibration.filter.apply(&played)?;
        let drive_peak = drive.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let scale = 0.9 / drive_peak; // peak-normalise to 90 % of full scale
        let drive: Vec<f64> = drive[..played.len()].iter().map(|v| v * scale).collect();
        let velocity = conv::convolve(&coil.drive_to_force(&drive)?, g)?;
        let velocity = &velocity[..played.len()];
        let recorded_velocity = record(velocity, scene, &mut rng, true)?;
        let recorded_loopback = record(&played, scene, &mut rng, false)?;
        let result = process_channel(&recorded_velocity, &recorded_loopback, &layout, &cfg)?;
        // The ideal: one compensated sweep through the same chain, linear, noise-free, one clock, no latency,
        // deconvolved linearly by its reference (a repeated reference would put the comb zeros of its spectrum into
        // the division).
        let mut linear_coil = coil.clone();
        linear_coil.nonlinearity = 0.0;
        let single = repeat(&excitation, 1, fs_hz);
        let single_drive: Vec<f64> =
            calibration.filter.apply(&single)?[..single.len()].iter().map(|v| v * scale).collect();
        let ideal_velocity = conv::convolve(&linear_coil.drive_to_force(&single_drive)?, g)?;
        let ideal = metaplate_dsp::deconv::deconvolve_with_reference(&ideal_velocity[..single.len()], &single, &cfg)?;
        let ir: Vec<f64> = result.ir.iter().map(|v| v / scale).collect();
        let ideal: Vec<f64> = ideal.iter().map(|v| v / scale).collect();
        rows.push(chain_row(k, &calibration, &result, &ir, &ideal, drive_peak));
        measured_irs.push(ir);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let path = args.out.join("measured_irs_centre_point.wav");
    let peak = measured_irs.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    let normalised: Vec<Vec<f64>> = measured_irs.iter().map(|ir| ir.iter().map(|v| v / peak).collect()).collect();
    wav::write_f32(&path, fs_hz, &normalised)?;
    let (x_m, y_m) = scene.grid.position_m(centre);
    Ok(json!({
        "point_index": centre, "x_m": x_m, "y_m": y_m,
        "protocol": "paper: 5 x 3 s linear sweep 62-625 Hz, compensated, loopback reference",
        "true_drift_ppm": (1.0 + DAQ_PPM * 1e-6) / (1.0 + AUDIO_PPM * 1e-6) * 1e6 - 1e6,
        "true_latency_samples": LATENCY_SAMPLES,
        "ldv_noise_rms_m_s": scene.ldv.noise_rms_m_s,
        "per_actuator": rows,
        "irs_wav": path.display().to_string(),
    }))
}

struct Calibration {
    filter: kirkeby::KirkebyFilter,
    flatness_db: (f64, f64),
}

/// Calibrates one coil as the paper does: a 3 s linear sweep from 50 to 625 Hz, its force response (deconvolved
/// two-sided, see `DeconvConfig::calibration`), the Kirkeby inverse, and a verification through it: the compensated
/// response as the full-length spectral ratio, its deviation from its median over the scan band 62 to 625 Hz, dB.
fn calibrate(coil: &VoiceCoil) -> anyhow::Result<Calibration> {
    let fs_hz = coil.sample_rate_hz;
    let sweep = SweepSpec { f1_hz: 50.0, amplitude: 0.5, ..SweepSpec::default() }.generate()?;
    let cfg = DeconvConfig { sample_rate_hz: fs_hz, ..DeconvConfig::calibration() };
    let mut recorded = sweep.clone();
    recorded.resize(sweep.len() + cfg.ir_len, 0.0);
    let response = deconvolve(&coil.drive_to_force(&recorded)?, &sweep, &cfg)?;
    let filter = kirkeby::design(&response, &KirkebyConfig::calibration(&cfg))?;
    let verified = coil.drive_to_force(&filter.apply(&sweep)?)?;
    let n = fft::fast_len(verified.len())?;
    let (out, inp) = (fft::forward(&verified, n)?, fft::forward(&sweep, n)?);
    let mut levels_db: Vec<f64> = (0..out.len())
        .filter(|&i| (62.0..=625.0).contains(&fft::bin_freq_hz(i, n, fs_hz)))
        .map(|i| 20.0 * (out[i] / inp[i]).norm().log10())
        .collect();
    if levels_db.is_empty() {
        bail!("internal: no bin in the calibration band");
    }
    levels_db.sort_by(f64::total_cmp);
    let median = levels_db[levels_db.len() / 2];
    let flatness_db = (levels_db[0] - median, levels_db[levels_db.len() - 1] - median);
    Ok(Calibration { filter, flatness_db })
}

/// `repetitions` copies of `x` back to back, then one second of silence for the responses to ring out.
fn repeat(x: &[f64], repetitions: usize, fs_hz: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len() * repetitions + fs_hz as usize);
    for _ in 0..repetitions {
        out.extend_from_slice(x);
    }
    out.resize(out.len() + fs_hz as usize, 0.0);
    out
}

/// What the DAQ records of a signal played on the audio interface's clock: latency and clock drift (band-limited
/// resampling), and for the velocity channel the LDV's noise and the DAQ's 16-bit quantisation over its range.
fn record(
    played: &[f64],
    scene: &Scene,
    rng: &mut rand_chacha::ChaCha8Rng,
    is_velocity: bool,
) -> anyhow::Result<Vec<f64>> {
    // Recorder sample n sees the player at position (n - latency) * ratio.
    let ratio = (1.0 + AUDIO_PPM * 1e-6) / (1.0 + DAQ_PPM * 1e-6);
    let out_len = played.len() + LATENCY_SAMPLES.ceil() as usize + 64;
    let interpolator = Interpolator::for_band(700.0, scene.daq.sample_rate_hz);
    let mut recorded = interpolator.resample(played, -LATENCY_SAMPLES * ratio, ratio, out_len)?;
    if is_velocity {
        let noise = Normal::new(0.0, scene.ldv.noise_rms_m_s)?;
        let volts_per_m_s = scene.daq.volts_per_m_s;
        let lsb_v = 2.0 * scene.daq.range_v / f64::from(1u32 << scene.daq.bits.min(31));
        for v in &mut recorded {
            let volts = ((*v + noise.sample(rng)) * volts_per_m_s).clamp(-scene.daq.range_v, scene.daq.range_v);
            *v = (volts / lsb_v).round() * lsb_v / volts_per_m_s;
        }
    }
    Ok(recorded)
}

fn chain_row(
    actuator: usize,
    calibration: &Calibration,
    result: &ChannelResult,
    ir: &[f64],
    ideal: &[f64],
    drive_peak: f64,
) -> Value {
    let error: f64 = ir.iter().zip(ideal).map(|(a, b)| (a - b).powi(2)).sum();
    let energy: f64 = ideal.iter().map(|b| b * b).sum();
    json!({
        "actuator": actuator,
        "kirkeby_max_boost_db": calibration.filter.max_boost_db,
        "compensated_flatness_db": [calibration.flatness_db.0, calibration.flatness_db.1],
        "drive_peak_before_normalisation": drive_peak,
        "snr_db": result.snr_db,
        "drift_ppm": result.drift_ppm,
        "latency_samples": result.latency_samples,
        "error_db": 10.0 * (error / energy).log10(),
    })
}

fn print_table(summary: &Value) {
    let disp = |plate: &str, f: f64| {
        summary["plates"][plate]["dispersion"]["points"]
            .as_array()
            .and_then(|ps| ps.iter().find(|p| p["freq_hz"].as_f64() == Some(f)))
            .map(|p| p["wavelength_m"].as_f64().unwrap_or(f64::NAN))
            .unwrap_or(f64::NAN)
    };
    let ratios: Vec<f64> =
        DISPERSION_FREQS_HZ.iter().map(|&f| disp("homogeneous", f) / disp("metamaterial", f)).collect();
    let (rmin, rmax) = ratios.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), &r| (a.min(r), b.max(r)));
    println!("\n{:<52} {:>16} {:>16}", "quantity", "paper", "metaplate");
    println!(
        "{:<52} {:>16} {:>13.1} cm",
        "wavelength, metamaterial, 75 Hz",
        "11.3 cm",
        disp("metamaterial", 75.0) * 100.0
    );
    println!(
        "{:<52} {:>16} {:>13.1} cm",
        "wavelength, metamaterial, 600 Hz",
        "2.5 cm",
        disp("metamaterial", 600.0) * 100.0
    );
    println!(
        "{:<52} {:>16} {:>7.1} to {:.1}",
        "homogeneous / metamaterial wavelength (k-space)", "2.1 to 4.8", rmin, rmax
    );
    let rows = summary["measurement_chain"]["per_actuator"].as_array().cloned().unwrap_or_default();
    let worst = |key: &str| rows.iter().filter_map(|r| r[key].as_f64()).fold(f64::NEG_INFINITY, f64::max);
    let best = |key: &str| rows.iter().filter_map(|r| r[key].as_f64()).fold(f64::INFINITY, f64::min);
    println!("\nmeasurement chain, centre point, 8 actuators (paper protocol, 50 ppm drift, LDV noise, 16-bit DAQ):");
    println!(
        "  Green's function error against the noise-free linear chain: {:.1} dB (worst actuator)",
        worst("error_db")
    );
    println!("  SNR estimate from the repetitions: {:.1} to {:.1} dB", best("snr_db"), worst("snr_db"));
    println!(
        "  drift estimated {:.2} to {:.2} ppm (true {:.2})",
        best("drift_ppm"),
        worst("drift_ppm"),
        summary["measurement_chain"]["true_drift_ppm"].as_f64().unwrap_or(f64::NAN)
    );
    let flat: Vec<f64> = rows
        .iter()
        .flat_map(|r| r["compensated_flatness_db"].as_array().cloned().unwrap_or_default())
        .filter_map(|v| v.as_f64())
        .collect();
    let (lo, hi) = flat.iter().fold((0.0_f64, 0.0_f64), |(a, b), &v| (a.min(v), b.max(v)));
    println!("  Kirkeby-compensated actuators flat within {lo:+.2} / {hi:+.2} dB over 62 to 625 Hz");
}
