//! Loading a full-size dataset into `G(omega)`: 1225 points x 8 actuators, impulse responses of 0.5 s at 24 kHz
//! (470 MB as f32), written once (synthetic decaying noise) to a temporary directory. Times, per run: a raw read of
//! the batch files, `Dataset::open` (read, SHA-256 of every file, Parquet decode), `Dataset::open_with` without
//! checksums (read and decode only), and `PropagationMatrices::from_dataset` (FFTs, band 75 to 400 Hz). The files
//! were just written, so the page cache is warm: the raw read is a memory copy, not the disk; `dd` of the files
//! after `echo 3 > /proc/sys/vm/drop_caches` gives the cold disk speed (`METAPLATE_BENCH_KEEP=1` keeps the
//! dataset and prints where). `cargo bench -p metaplate-control --bench load`.

#![allow(clippy::unwrap_used, missing_docs)] // a benchmark harness: failures are failures, no public API

use std::time::Instant;

use metaplate_control::PropagationMatrices;
use metaplate_store::{
    BATCH_DIR, Dataset, DatasetMeta, DatasetWriter, GridSpec, IfExists, IrMeta, IrRecord, ReadOptions, SceneId,
};

const FS_HZ: f64 = 24_000.0;
const IR_LEN: usize = 12_000;

fn write(dir: &std::path::Path) -> u64 {
    let grid = GridSpec { nx: 49, ny: 25, spacing_m: 0.005, origin_x_m: -0.12, origin_y_m: -0.06 };
    let meta = DatasetMeta::new(
        "bench",
        serde_json::Map::new(),
        SceneId { name: "none".into(), hash: "0".into() },
        "0",
        1,
        grid,
    );
    let mut writer = DatasetWriter::create(dir, meta, IfExists::Replace).unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    for iy in 0..25 {
        let mut records = Vec::new();
        for ix in 0..49 {
            for actuator in 0..8 {
                let meta = IrMeta::at_grid(&grid, ix, iy, actuator, FS_HZ).unwrap();
                let ir = (0..IR_LEN)
                    .map(|i| {
                        state ^= state << 13;
                        state ^= state >> 7;
                        state ^= state << 17;
                        let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                        (u * (-(i as f64) / 2400.0).exp()) as f32
                    })
                    .collect();
                records.push(IrRecord { meta, ir });
            }
        }
        writer.commit_batch(&records).unwrap();
    }
    let manifest = writer.finish().unwrap();
    manifest.batches.iter().map(|b| b.size_bytes).sum()
}

fn main() {
    let dir = std::env::temp_dir().join(format!("metaplate-load-bench-{}", std::process::id()));
    let t = Instant::now();
    let bytes = write(&dir);
    eprintln!("wrote {:.1} MB of batches in {:.1} s", bytes as f64 / 1e6, t.elapsed().as_secs_f64());
    let raw_mb = (1225 * 8 * IR_LEN * 4) as f64 / 1e6;
    for run in 0..3 {
        // Raw read of the batch files (warm page cache after the first pass).
        let t = Instant::now();
        let mut read = 0;
        for entry in std::fs::read_dir(dir.join(BATCH_DIR)).unwrap() {
            read += std::fs::read(entry.unwrap().path()).unwrap().len();
        }
        let raw_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let dataset = Dataset::open(&dir).unwrap();
        let open_s = t.elapsed().as_secs_f64();
        drop(dataset);
        let t = Instant::now();
        let dataset = Dataset::open_with(&dir, ReadOptions { verify_checksums: false }).unwrap();
        let decode_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let g = PropagationMatrices::from_dataset(&dataset, (75.0, 400.0), None).unwrap();
        let g_s = t.elapsed().as_secs_f64();
        eprintln!(
            "run {run}: raw read {:.1} MB in {raw_s:.3} s ({:.0} MB/s); Dataset::open {open_s:.3} s ({:.0} MB/s), \
             without checksums {decode_s:.3} s ({:.0} MB/s); from_dataset ({} bins) {g_s:.3} s ({:.0} MB/s); \
             open + G: {:.0} MB/s of f32 impulse responses ({raw_mb:.0} MB)",
            read as f64 / 1e6,
            read as f64 / 1e6 / raw_s,
            read as f64 / 1e6 / open_s,
            read as f64 / 1e6 / decode_s,
            g.n_bins(),
            raw_mb / g_s,
            raw_mb / (open_s + g_s)
        );
    }
    if std::env::var_os("METAPLATE_BENCH_KEEP").is_some() {
        eprintln!("kept the dataset in {} (METAPLATE_BENCH_KEEP)", dir.display());
    } else {
        let _ = std::fs::remove_dir_all(&dir);
    }
}
