//! Writes and re-reads a synthetic dataset and reports throughput and file size; a by-hand benchmark, not a test.
//!
//! `cargo bench -p metaplate-store --bench write_throughput -- DIR [POINTS ACTUATORS IR_LEN BATCH_POINTS]`
//!
//! Defaults: the paper's full dataset, 1225 points (49 x 25) x 8 actuators x 12000 f32 samples, one batch per 25
//! points (a row of the grid). DIR must not exist or be empty; it is left behind for inspection (pyarrow, polars).

mod common;

use std::error::Error;
use std::time::Instant;

use metaplate_store::{Dataset, DatasetWriter, IfExists, IrMeta, IrRecord, Status};

fn main() -> Result<(), Box<dyn Error>> {
    let args = common::args();
    let dir = args.first().ok_or("usage: write_throughput DIR [POINTS ACTUATORS IR_LEN BATCH_POINTS]")?;
    let points = common::arg(&args, 1, 1225)?;
    let actuators = u16::try_from(common::arg(&args, 2, 8)?)?;
    let ir_len = common::arg(&args, 3, 12_000)?;
    let batch_points = common::arg(&args, 4, 25)?.max(1);
    let meta = common::synthetic_meta("write-throughput", points, actuators, ir_len);
    let grid = meta.grid;
    let mut ir = common::noise_responses();

    let mut writer = DatasetWriter::create(dir, meta, IfExists::Refuse)?;
    let (mut generate_s, mut write_s) = (0.0, 0.0);
    for first in (0..points).step_by(batch_points) {
        let start = Instant::now();
        let mut batch = Vec::new();
        for p in first..(first + batch_points).min(points) {
            let (ix, iy) = grid.indices(p);
            for actuator in 0..actuators {
                let mut meta = IrMeta::at_grid(&grid, u32::try_from(ix)?, u32::try_from(iy)?, actuator, 24_000.0)?;
                meta.status = Some(Status::GroundTruth);
                batch.push(IrRecord { meta, ir: ir(ir_len) });
            }
        }
        generate_s += start.elapsed().as_secs_f64();
        let start = Instant::now();
        writer.commit_batch(&batch)?;
        write_s += start.elapsed().as_secs_f64();
    }
    let start = Instant::now();
    let manifest = writer.finish()?;
    write_s += start.elapsed().as_secs_f64();

    let raw_mb = (points * usize::from(actuators) * ir_len * 4) as f64 / 1e6;
    let file_mb = manifest.batches.iter().map(|b| b.size_bytes).sum::<u64>() as f64 / 1e6;
    println!(
        "{points} points x {actuators} actuators x {ir_len} samples: {raw_mb:.1} MB of f32 in {} files, {file_mb:.1} MB \
         on disk ({:.3} of raw)",
        manifest.batches.len(),
        file_mb / raw_mb
    );
    println!("generate {generate_s:.2} s; write (encode, hash, fsync) {write_s:.2} s = {:.0} MB/s", raw_mb / write_s);

    let start = Instant::now();
    let dataset = Dataset::open(dir)?;
    let read_s = start.elapsed().as_secs_f64();
    println!("open (read, verify, decode) {read_s:.2} s = {:.0} MB/s; {} rows", raw_mb / read_s, dataset.len());
    Ok(())
}
