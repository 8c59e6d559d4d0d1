//! Cost of one scan commit (one point: 8 rows of 12000-sample responses) and of resuming a full dataset; a by-hand
//! benchmark, not a test.
//!
//! `cargo run --release -p metaplate-store --example commit_cost -- DIR [POINTS ACTUATORS IR_LEN]`
//!
//! Defaults: the paper's scan, 1225 points x 8 actuators x 12000 samples, one commit per point. DIR must not exist
//! or be empty; it is left behind.

use std::error::Error;
use std::time::Instant;

use metaplate_store::{DatasetMeta, DatasetWriter, GridSpec, IfExists, IrMeta, IrRecord, SceneId, Status};

fn arg(args: &[String], i: usize, default: usize) -> Result<usize, Box<dyn Error>> {
    Ok(match args.get(i) {
        Some(s) => s.parse()?,
        None => default,
    })
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).ok_or("usage: commit_cost DIR [POINTS ACTUATORS IR_LEN]")?;
    let points = arg(&args, 2, 1225)?;
    let actuators = u16::try_from(arg(&args, 3, 8)?)?;
    let ir_len = arg(&args, 4, 12_000)?;
    let grid = GridSpec::centred(49, points.div_ceil(49).max(1), 0.005);
    let config = serde_json::json!({"points": points, "actuators": actuators, "ir_len": ir_len});
    let meta = DatasetMeta::new(
        "commit-cost",
        config.as_object().cloned().unwrap_or_default(),
        SceneId { name: "synthetic".into(), hash: "none".into() },
        env!("CARGO_PKG_VERSION"),
        1,
        grid,
    );
    // Noise-like decaying responses: incompressible, like measurements.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut ir = |len: usize| -> Vec<f32> {
        (0..len)
            .map(|i| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * (-(i as f32) / len as f32 * 6.0).exp()
            })
            .collect()
    };
    let mut writer = DatasetWriter::create(dir, meta.clone(), IfExists::Refuse)?;
    let mut costs_ms = Vec::with_capacity(points);
    for p in 0..points {
        let (ix, iy) = grid.indices(p);
        let mut batch = Vec::new();
        for actuator in 0..actuators {
            let mut meta = IrMeta::at_grid(&grid, u32::try_from(ix)?, u32::try_from(iy)?, actuator, 24_000.0)?;
            meta.status = Some(Status::Valid);
            meta.snr_db = Some(40.0);
            batch.push(IrRecord { meta, ir: ir(ir_len) });
        }
        let start = Instant::now();
        writer.commit_batch(&batch)?;
        costs_ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    drop(writer);
    let total_ms: f64 = costs_ms.iter().sum();
    costs_ms.sort_by(f64::total_cmp);
    let pick = |q: f64| costs_ms[((costs_ms.len() - 1) as f64 * q).round() as usize];
    println!(
        "{points} commits of {actuators} x {ir_len} samples: mean {:.2} ms, median {:.2} ms, p99 {:.2} ms, max {:.2} ms",
        total_ms / points as f64,
        pick(0.5),
        pick(0.99),
        pick(1.0)
    );
    let start = Instant::now();
    let (_writer, report) = DatasetWriter::resume(dir, &meta, false)?;
    println!(
        "resume: {:.3} s wall ({} keys committed, {:.0} MB verified by SHA-256, {} quarantined)",
        start.elapsed().as_secs_f64(),
        report.committed.len(),
        report.verified_bytes as f64 / 1e6,
        report.quarantined.len()
    );
    Ok(())
}
