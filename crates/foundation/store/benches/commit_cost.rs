//! Cost of one scan commit (one point: 8 rows of 12000-sample responses) and of resuming a full dataset; a by-hand
//! benchmark, not a test.
//!
//! `cargo bench -p metaplate-store --bench commit_cost -- DIR [POINTS ACTUATORS IR_LEN]`
//!
//! Defaults: the paper's scan, 1225 points x 8 actuators x 12000 samples, one commit per point. DIR must not exist
//! or be empty; it is left behind.

mod common;

use std::error::Error;
use std::time::Instant;

use metaplate_store::{DatasetWriter, IfExists, IrMeta, IrRecord, Status};

fn main() -> Result<(), Box<dyn Error>> {
    let args = common::args();
    let dir = args.first().ok_or("usage: commit_cost DIR [POINTS ACTUATORS IR_LEN]")?;
    let points = common::arg(&args, 1, 1225)?;
    let actuators = u16::try_from(common::arg(&args, 2, 8)?)?;
    let ir_len = common::arg(&args, 3, 12_000)?;
    let meta = common::synthetic_meta("commit-cost", points, actuators, ir_len);
    let grid = meta.grid;
    let mut ir = common::noise_responses();
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
