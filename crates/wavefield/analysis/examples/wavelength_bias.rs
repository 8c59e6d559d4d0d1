//! Reports on the k-space wavelength estimator's bias on synthetic fields (measurements, not tests):
//! `cargo run --release -p metaplate-analysis --example wavelength_bias -- [table|scatter]`
//! (environment: `PAD=<zero_pad_factor>`, `MEAN=0` to keep the mean).
#![allow(clippy::unwrap_used)] // a report on fixed synthetic inputs: a failure is a bug to see at once

// The synthetic fields of the integration tests, shared rather than copied (the module allows its own dead code).
#[path = "../tests/common/mod.rs"]
mod common;

use common::*;
use metaplate_analysis::wavelength::{BinWeighting, KSpaceMethod, KSpaceOptions, estimate_wavelength};
use num_complex::Complex64;

const LAMBDAS_M: [f64; 5] = [0.025, 0.05, 0.10, 0.15, 0.25];

fn cases(lambda_m: f64) -> Vec<(&'static str, Vec<Complex64>)> {
    let mut v = vec![
        ("plane 0deg", plane_wave(lambda_m, 0.0)),
        ("plane 30deg", plane_wave(lambda_m, 30f64.to_radians())),
        ("plane 90deg", plane_wave(lambda_m, 90f64.to_radians())),
        ("cyl outside", cylindrical_wave(lambda_m, 0.16, 0.09)),
        ("cyl inside", cylindrical_wave(lambda_m, 0.0325, 0.0125)),
    ];
    for seed in 0..4 {
        v.push(("standing", standing_mixture(lambda_m, 24, seed)));
    }
    v
}

fn print_bias_table() {
    let mask = stadium_mask();
    let pad: usize =
        std::env::var("PAD").ok().and_then(|v| v.parse().ok()).unwrap_or(KSpaceOptions::default().zero_pad_factor);
    let remove_mean = std::env::var("MEAN").map_or(true, |v| v != "0");
    println!("zero_pad_factor {pad}, remove_mean {remove_mean}");
    let variants = [
        ("contour/uniform", KSpaceMethod::HalfMaxContour, BinWeighting::Uniform, 0.0),
        ("contour/energy", KSpaceMethod::HalfMaxContour, BinWeighting::Energy, 0.0),
        ("radial/uniform", KSpaceMethod::RadialProfile, BinWeighting::Uniform, 0.0),
        ("radial/energy", KSpaceMethod::RadialProfile, BinWeighting::Energy, 0.0),
    ];
    for (name, method, weighting, taper) in variants {
        let opts = KSpaceOptions {
            method,
            weighting,
            taper_width_m: taper,
            zero_pad_factor: pad,
            remove_mean,
            ..KSpaceOptions::default()
        };
        println!("\n{name}: relative bias of median (peak) [flags], per true wavelength");
        print!("{:<12}", "case");
        for l in LAMBDAS_M {
            print!("{:>22}", format!("{:.1} cm", l * 100.0));
        }
        println!();
        let labels = cases(0.1).into_iter().map(|c| c.0).collect::<Vec<_>>();
        for (ci, label) in labels.iter().enumerate() {
            print!("{label:<12}");
            for l in LAMBDAS_M {
                let field = &cases(l)[ci].1;
                match estimate_wavelength(field, &mask, NX, NY, SPACING_M, &opts) {
                    Ok(e) => {
                        let f = e.flags;
                        let flag = format!(
                            "{}{}{}",
                            if f.under_resolved { "U" } else { "" },
                            if f.near_nyquist { "N" } else { "" },
                            if f.touches_dc_exclusion { "D" } else { "" }
                        );
                        print!("{:>22}", format!("{:+.3} ({:+.3}){}", e.median_m / l - 1.0, e.peak_m / l - 1.0, flag));
                    }
                    Err(err) => print!("{:>22}", format!("err {err}")),
                }
            }
            println!();
        }
    }
}

fn print_standing_mixture_scatter() {
    let mask = stadium_mask();
    let opts = KSpaceOptions::default();
    println!("default options, 64 standing mixtures of 24 waves: relative bias of the median");
    for l in LAMBDAS_M {
        let biases: Vec<f64> = (0..64)
            .map(|seed| {
                let e = estimate_wavelength(&standing_mixture(l, 24, seed), &mask, NX, NY, SPACING_M, &opts).unwrap();
                e.median_m / l - 1.0
            })
            .collect();
        let mean = biases.iter().sum::<f64>() / biases.len() as f64;
        let sd = (biases.iter().map(|b| (b - mean) * (b - mean)).sum::<f64>() / (biases.len() - 1) as f64).sqrt();
        let worst = biases.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        println!("{:>5.1} cm: mean {mean:+.4}  sd {sd:.4}  worst |bias| {worst:.4}", l * 100.0);
    }
}

/// `table` (default): the relative bias of the k-space estimator per synthetic case and wavelength (options from the
/// environment: `PAD=n`, `MEAN=0`); `scatter`: the spread of the estimate over reverberant (standing-wave) fields.
fn main() {
    match std::env::args().nth(1).as_deref() {
        None | Some("table") => print_bias_table(),
        Some("scatter") => print_standing_mixture_scatter(),
        Some(other) => eprintln!("unknown report `{other}`: use `table` or `scatter`"),
    }
}
