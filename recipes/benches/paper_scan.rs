//! The full paper protocol on the built-in metamaterial scene in fast-forward: a by-hand benchmark, not a test.
//!
//! `cargo bench -p metaplate-recipes --bench paper_scan -- [--points N] [--protocol NAME]`
//!
//! Scans every measurable point of the full grid (or the first N of its serpentine path), uncalibrated, with
//! `--protocol` (default `paper`: 3 s sweeps x 5 per actuator), into a temporary directory, and prints: wall time,
//! simulated (rig clock) hours and their ratio, the time spent in commits (absolute, % of wall, % of simulated scan
//! time), and the resume start-up time (the finished dataset re-opened with resume: wall time until the scan's
//! `Started` event, which comes after verifying every committed file). The plate's Green's functions are cached in
//! the target's temporary directory (`target/tmp/metaplate-greens`): the first run computes them (minutes for the full grid).

use std::error::Error;
use std::time::Instant;

use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPoints, scan};
use metaplate_recipes::{Event, Output, RunControl};

struct Args {
    points: Option<usize>,
    protocol: String,
}

fn parse_args() -> Result<Args, Box<dyn Error>> {
    let mut args = Args { points: None, protocol: "paper".into() };
    // `cargo bench` passes `--bench` to a harness-less bench: not ours to parse.
    let mut it = std::env::args().skip(1).filter(|a| a != "--bench");
    while let Some(a) = it.next() {
        match a.as_str() {
            "--points" => args.points = Some(it.next().ok_or("--points needs a number")?.parse()?),
            "--protocol" => args.protocol = it.next().ok_or("--protocol needs a name")?,
            other => return Err(format!("unknown argument `{other}` (known: --points N, --protocol NAME)").into()),
        }
    }
    Ok(args)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = parse_args()?;
    let scene = Scene::builtin("metamaterial")?;
    let mut plan = ScanPoints::new(scene.grid, &scene.grid_mask(), None)?;
    if let Some(n) = args.points {
        plan.points.truncate(n.max(1));
    }
    let cfg = ScanConfig { protocol: ExcitationProtocol::by_name(&args.protocol)?, seed: 1, ..ScanConfig::default() };
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("metaplate-greens");
    let options = LabOptions { points: Some(plan.points.clone()), cache_dir: Some(cache), ..LabOptions::default() };
    let lab_started = Instant::now();
    let lab = MockLab::new(&scene, &options)?;
    println!(
        "lab ready in {:.1} s (Green's functions of {} points)",
        lab_started.elapsed().as_secs_f64(),
        plan.points.len()
    );

    let dir = tempfile::tempdir()?;
    let mut out = Output {
        dir: dir.path().to_path_buf(),
        scene: scene.id(),
        software_version: env!("CARGO_PKG_VERSION").into(),
        resume: false,
        force: false,
        preflight: None,
    };
    let mut rig = lab.rig()?;
    let started = Instant::now();
    let mut progress = |e: &Event| {
        if let Event::Committed { done, total, .. } = e
            && (done % 100 == 0 || done == total)
        {
            eprintln!("{done}/{total} points, {:.0} s", started.elapsed().as_secs_f64());
        }
    };
    let summary = scan(&mut rig, &plan, None, &cfg, &out, &RunControl::new(), &mut progress)?;
    let wall_s = started.elapsed().as_secs_f64();
    let points = summary.committed_now as f64;
    println!("protocol {}: {} points x {} actuators", cfg.protocol.name, summary.committed_now, scene.actuators.len());
    println!("statuses {:?}, {} deferred", summary.statuses, summary.deferred);
    println!(
        "wall {wall_s:.1} s ({:.3} s per point); simulated {:.2} h ({:.1} s per point); {:.0} x real time",
        wall_s / points,
        summary.clock_s / 3600.0,
        summary.clock_s / points,
        summary.clock_s / wall_s
    );
    println!(
        "commits {:.3} s ({:.1} ms per point): {:.2} % of wall, {:.4} % of simulated scan time",
        summary.commit_s,
        summary.commit_s / points * 1e3,
        100.0 * summary.commit_s / wall_s,
        100.0 * summary.commit_s / summary.clock_s
    );

    // Resume start-up: a restarted program (a fresh lab, its Green's functions from the cache, not timed) re-opens
    // the finished dataset; timed from the call to the scan's first event.
    let lab = MockLab::new(&scene, &options)?;
    let mut rig = lab.rig()?;
    out.resume = true;
    let resume_started = Instant::now();
    let mut started_after_s = None;
    let mut on_start = |e: &Event| {
        if matches!(e, Event::Started { .. }) && started_after_s.is_none() {
            started_after_s = Some(resume_started.elapsed().as_secs_f64());
        }
    };
    let resumed = scan(&mut rig, &plan, None, &cfg, &out, &RunControl::new(), &mut on_start)?;
    let startup_s = started_after_s.ok_or("the resumed scan never started")?;
    println!(
        "resume start-up {startup_s:.3} s (verifying {} committed points); the resume committed {} more",
        resumed.committed, resumed.committed_now
    );
    Ok(())
}
