//! What the store's hand-run benchmarks share: their command line, a synthetic dataset's metadata and
//! measurement-like responses.

use std::error::Error;

use metaplate_core::rng::SplitMix64;
use metaplate_store::{DatasetMeta, GridSpec};

/// The benchmark's own arguments: the command line without the program name and the `--bench` flag `cargo bench`
/// adds.
pub fn args() -> Vec<String> {
    std::env::args().skip(1).filter(|a| a != "--bench").collect()
}

/// Argument `i` as a whole number, `default` when absent.
pub fn arg(args: &[String], i: usize, default: usize) -> Result<usize, Box<dyn Error>> {
    Ok(match args.get(i) {
        Some(s) => s.parse()?,
        None => default,
    })
}

/// Metadata of a synthetic dataset of `points` points (rows of the paper's 49-point width, 5 mm apart).
pub fn synthetic_meta(recipe: &str, points: usize, actuators: u16, ir_len: usize) -> DatasetMeta {
    let grid = GridSpec::centred(49, points.div_ceil(49).max(1), 0.005);
    let config = serde_json::json!({"points": points, "actuators": actuators, "ir_len": ir_len});
    DatasetMeta::new(
        recipe,
        config.as_object().cloned().unwrap_or_default(),
        metaplate_core::scene::SceneId { name: "synthetic".into(), hash: "none".into() },
        env!("CARGO_PKG_VERSION"),
        1,
        grid,
    )
}

/// Decaying noise-like responses of `len` samples, one per call: incompressible like real measurements (a smooth
/// signal would flatter the encoder).
pub fn noise_responses() -> impl FnMut(usize) -> Vec<f32> {
    let mut rng = SplitMix64::new(1, 0x0062_656e_6368); // "bench"
    move |len| (0..len).map(|i| (rng.uniform() as f32 - 0.5) * (-(i as f32) / len as f32 * 6.0).exp()).collect()
}
