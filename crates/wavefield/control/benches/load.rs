//! Loading a full-size dataset into `G(omega)`: 1225 points x 8 actuators, impulse responses of 0.5 s at 24 kHz
//! (470 MB as f32, 25 batch files of one grid row each), written once (synthetic decaying noise) to a temporary
//! directory. Times, per run, each stage with its throughput in MB/s and the CPU time of the whole process (all
//! threads; CPU time over wall time shows how many cores a stage kept busy, and how much another load on the machine
//! took from it):
//! - raw read: `std::fs::read` of every batch file, one after the other, each dropped before the next;
//! - SHA-256: `metaplate_store::sha256` of every file on one thread (the hash alone, wall time);
//! - `Dataset::open`: read, SHA-256 of every file, Parquet decode, checks (on one thread per core);
//! - `Dataset::open_with` without checksums: read, decode and checks only;
//! - `PropagationMatrices::from_dataset`: FFTs, band 75 to 400 Hz (MB/s of f32 impulse responses).
//!
//! The files were just written, so the page cache is warm: the raw read is a memory copy, not the disk. Environment:
//! - `METAPLATE_BENCH_KEEP=1` keeps the dataset and prints where; `METAPLATE_BENCH_DIR=<that directory>` reads it
//!   again instead of writing a new one;
//! - `METAPLATE_BENCH_COLD=1` drops the page cache (`echo 1 > /proc/sys/vm/drop_caches`: needs root, and slows
//!   everything else on the machine for a moment) before the raw read and before each open, so that those stages
//!   read the disk.
//!
//! The machine's load average is printed first: other work on it slows every stage.
//! `cargo bench -p metaplate-control --bench load`.

#![allow(clippy::unwrap_used, missing_docs)] // a benchmark harness: failures are failures, no public API

use std::path::{Path, PathBuf};
use std::time::Instant;

use metaplate_control::PropagationMatrices;
use metaplate_store::{
    BATCH_DIR, Dataset, DatasetMeta, DatasetWriter, GridSpec, IfExists, IrMeta, IrRecord, ReadOptions, SceneId,
};

const FS_HZ: f64 = 24_000.0;
const IR_LEN: usize = 12_000;

fn write(dir: &Path) -> u64 {
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

/// CPU time of this process so far, all threads (user + system), s; `None` off Linux. Clock ticks of 10 ms
/// (`CLK_TCK` is 100 on Linux), fine for stages of tenths of a second.
fn cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces, hence the last ')'): state is field 3, utime 14, stime 15.
    let fields: Vec<&str> = stat.get(stat.rfind(')')? + 2..)?.split(' ').collect();
    let ticks = |i: usize| fields.get(i - 3)?.parse::<f64>().ok();
    Some((ticks(14)? + ticks(15)?) / 100.0)
}

/// A stage's wall time, CPU time and throughput of `mb` megabytes, as one line.
struct Stage {
    wall: Instant,
    cpu: Option<f64>,
}

impl Stage {
    fn start() -> Self {
        Self { wall: Instant::now(), cpu: cpu_s() }
    }

    fn end(self, mb: f64) -> String {
        let wall = self.wall.elapsed().as_secs_f64();
        let cpu = match (self.cpu, cpu_s()) {
            (Some(a), Some(b)) => format!(", cpu {:.2} s", b - a),
            _ => String::new(),
        };
        format!("{wall:.3} s ({:.0} MB/s{cpu})", mb / wall)
    }
}

/// With `METAPLATE_BENCH_COLD` set, drops the page cache so that the next stage reads the disk.
fn maybe_drop_caches() {
    if std::env::var_os("METAPLATE_BENCH_COLD").is_some() {
        let _ = std::process::Command::new("sync").status();
        if let Err(e) = std::fs::write("/proc/sys/vm/drop_caches", "1") {
            eprintln!("cannot drop the page cache ({e}): this stage reads it warm");
        }
    }
}

fn main() {
    if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        eprintln!("load average {} ({cores} cores)", load.split(' ').take(3).collect::<Vec<_>>().join(" "));
    }
    let (dir, bytes) = match std::env::var_os("METAPLATE_BENCH_DIR") {
        Some(dir) => {
            let dir = PathBuf::from(dir);
            let bytes = Dataset::open(&dir).unwrap().manifest().batches.iter().map(|b| b.size_bytes).sum();
            eprintln!("reading the dataset in {} (METAPLATE_BENCH_DIR)", dir.display());
            (dir, bytes)
        }
        None => {
            let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join(format!("metaplate-load-bench-{}", std::process::id()));
            let t = Stage::start();
            let bytes = write(&dir);
            eprintln!("wrote {:.1} MB of batches in {}", bytes as f64 / 1e6, t.end(bytes as f64 / 1e6));
            (dir, bytes)
        }
    };
    let file_mb = bytes as f64 / 1e6;
    let ir_mb = (1225 * 8 * IR_LEN * 4) as f64 / 1e6;
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir.join(BATCH_DIR)).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    for run in 0..3 {
        // Raw read of the batch files (warm page cache after the first pass), each dropped before the next.
        maybe_drop_caches();
        let t = Stage::start();
        let mut read = 0;
        for f in &files {
            read += std::fs::read(f).unwrap().len();
        }
        assert_eq!(read as u64, bytes);
        let raw = t.end(file_mb);
        // The hash alone, timed file by file after reading it.
        let mut sha_s = 0.0;
        for f in &files {
            let contents = std::fs::read(f).unwrap();
            let t = Instant::now();
            std::hint::black_box(metaplate_store::sha256(&contents));
            sha_s += t.elapsed().as_secs_f64();
        }
        let sha = format!("{sha_s:.3} s ({:.0} MB/s)", file_mb / sha_s);
        maybe_drop_caches();
        let t = Stage::start();
        let dataset = Dataset::open(&dir).unwrap();
        let open = t.end(file_mb);
        drop(dataset);
        maybe_drop_caches();
        let t = Stage::start();
        let dataset = Dataset::open_with(&dir, ReadOptions { verify_checksums: false }).unwrap();
        let decode = t.end(file_mb);
        let t = Stage::start();
        let g = PropagationMatrices::from_dataset(&dataset, (75.0, 400.0), None).unwrap();
        let fft = t.end(ir_mb);
        eprintln!(
            "run {run} ({file_mb:.1} MB of files, {ir_mb:.0} MB of f32 responses):\n  raw read {raw}\n  \
             SHA-256, 1 thread {sha}\n  Dataset::open {open}\n  open without checksums {decode}\n  \
             from_dataset ({} bins) {fft}",
            g.n_bins()
        );
    }
    // A dataset named by METAPLATE_BENCH_DIR is not ours to remove.
    let ours = std::env::var_os("METAPLATE_BENCH_DIR").is_none();
    if ours && std::env::var_os("METAPLATE_BENCH_KEEP").is_some() {
        eprintln!("kept the dataset in {} (METAPLATE_BENCH_KEEP)", dir.display());
    } else if ours {
        let _ = std::fs::remove_dir_all(&dir);
    }
}
