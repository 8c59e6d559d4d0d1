//! The stand-in rig (`metaplate lab serve`) as a lab rehearses with it: `check --hardware` and a 7 x 5
//! `scan --hardware` on the hardware file it writes, every byte through the real backends (serialport to the Polytec
//! controller and the Zaber stages on pseudo-terminals, the NI-DAQmx loader into the stand-in library and its lab
//! link, libasound's `file` PCM into the rig's FIFO), with the mock lab behind them. The scan's Green's functions
//! against the lab's truth land within 1 dB of the same scan on `--scene`; Ctrl-C stops the rig and clears its
//! folder. Faults of the rig's instruments (the scene's, or a hardware file's mistakes) fail `check` by name. Its
//! galvo mirrors are taught through it.
//!
//! The rig needs the real backends: the binary's default features.
#![cfg(all(feature = "serial", feature = "zaber", feature = "nidaqmx", feature = "alsa", target_os = "linux"))]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use metaplate_core::scene::Scene;
use metaplate_store::Dataset;
use serde_json::Value;

use crate::common::{cache_dir, interrupt, metaplate, scratch};

/// The scan both runs make: the metamaterial plate's 7 x 5 grid (the Green's functions the check tests prepare),
/// each actuator alone with one 0.6 s sweep (the fastest protocol to play), uncalibrated.
const SCAN: &[&str] = &["--grid", "7x5", "--protocol", "sequential:0.6x1", "--uncalibrated"];

/// How much faster than real time the rig's DAQ acquires (the scan plays 35 x 8 sweeps: 66 s of test at 16, 91 s
/// at 8).
const SPEED: &str = "16";

/// The median error may differ by this much, dB: what the rig promises a rehearsal. The two runs draw their noise
/// alike (keyed by the beam's site and the drive) but not identically (the rig's latency is its own), and the rig's
/// NI inputs do not quantise as the mock U6 does; measured, the two medians agree to 0.01 dB (docs/testing.md).
const MEDIAN_TOLERANCE_DB: f64 = 1.0;

/// A running `lab serve`; killed if a test fails before it stops it.
struct Served {
    child: Child,
    dir: PathBuf,
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Served {
    fn hardware(&self) -> String {
        self.dir.join("hardware.toml").to_str().unwrap().to_owned()
    }
}

/// Starts `metaplate lab serve` of the metamaterial scene's 7 x 5 grid in `dir`, and waits for its hardware file.
fn serve(dir: &Path) -> Served {
    serve_scene("metamaterial", dir, &[])
}

/// As [`serve`], for scene `scene` (a name or a file), with `extra` arguments.
fn serve_scene(scene: &str, dir: &Path, extra: &[&str]) -> Served {
    let library = metaplate_fixtures::nidaqmx_stand_in();
    let log = std::fs::File::create(dir.with_extension("log")).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["lab", "serve", "--scene", scene, "--grid", "7x5", "--speed", SPEED])
        .args(extra)
        .arg("--out")
        .arg(dir)
        .arg("--nidaqmx-library")
        .arg(library)
        .arg("--cache-dir")
        .arg(cache_dir())
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .unwrap();
    let mut served = Served { child, dir: dir.to_path_buf() };
    // The first run of a test session may compute the plate's Green's functions.
    let deadline = Instant::now() + Duration::from_secs(600);
    while !dir.join("hardware.toml").exists() {
        if let Some(status) = served.child.try_wait().unwrap() {
            panic!("lab serve ended ({status}): {}", std::fs::read_to_string(dir.with_extension("log")).unwrap());
        }
        assert!(Instant::now() < deadline, "lab serve wrote no hardware file");
        std::thread::sleep(Duration::from_millis(100));
    }
    served
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The median error of a scan's Green's functions against the metamaterial lab's truth, dB.
fn median_error_db(scan: &Path) -> f64 {
    let scene = Scene::resolve("metamaterial").unwrap();
    let dataset = Dataset::open(scan).unwrap();
    let mut errors = metaplate_evaluation::truth::dataset_errors(&scene, &dataset, None, Some(&cache_dir())).unwrap();
    assert_eq!(errors.len(), 35 * 8, "every row compared");
    metaplate_dsp::stats::median(&mut errors).unwrap()
}

#[test]
fn check_and_a_7x5_scan_run_through_the_real_backends_on_the_stand_in_rig() {
    let root = scratch("standin", "rig");
    let served = serve(&root.join("rig"));
    let hardware = served.hardware();
    let written = std::fs::read_to_string(&hardware).unwrap();
    for backend in ["\"polytec\"", "\"zaber\"", "\"nidaqmx\"", "\"alsa\""] {
        assert!(written.contains(backend), "{written}");
    }

    let out = metaplate(&["check", "--hardware", &hardware, "--grid", "7x5", "--json"]);
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap_or_else(|_| panic!("{}", text(&out.stderr)));
    assert_eq!(out.status.code(), Some(0), "{report:#}\n{}", text(&out.stderr));
    assert_eq!(report["verdict"], "pass", "{report:#}");
    // The identities the real backends read from the mock devices.
    assert_eq!(report["rig"]["vibrometer"]["vendor"], "Polytec", "{report:#}");
    assert!(report["rig"]["daq"]["model"].as_str().unwrap().contains("USB-6211"), "{report:#}");

    let scan = root.join("scan");
    let mut args = vec!["scan", "--hardware", &hardware, "--out", scan.to_str().unwrap()];
    args.extend(SCAN);
    let out = metaplate(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));

    let reference = root.join("reference");
    let mut args = vec!["scan", "--scene", "metamaterial", "--out", reference.to_str().unwrap()];
    args.extend(SCAN);
    let out = metaplate(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));

    let (rig_db, scene_db) = (median_error_db(&scan), median_error_db(&reference));
    eprintln!("median error against the truth: stand-in rig {rig_db:.2} dB, --scene {scene_db:.2} dB");
    assert!((rig_db - scene_db).abs() <= MEDIAN_TOLERANCE_DB, "rig {rig_db:.2} dB, --scene {scene_db:.2} dB");

    // Ctrl-C stops the rig: it exits cleanly and takes what it put in its folder with it.
    let mut served = served;
    interrupt(&served.child);
    let status = served.child.wait().unwrap();
    assert!(status.success(), "{status}");
    for left in ["play.fifo", "lab.sock", "hardware.toml", "libnidaqmx_standin.so"] {
        assert!(!served.dir.join(left).exists(), "{left} is left");
    }
}

/// The metamaterial scene with `extra` TOML appended (its empty fault list dropped, so `extra` may add faults), as
/// a file in `dir`.
fn scene_file(dir: &Path, name: &str, extra: &str) -> String {
    let resolved =
        Command::new(env!("CARGO_BIN_EXE_metaplate")).args(["scene", "show", "metamaterial"]).output().unwrap();
    assert!(resolved.status.success(), "{}", text(&resolved.stderr));
    let path = dir.join(name);
    std::fs::write(&path, format!("{}\n{extra}", text(&resolved.stdout).replace("faults = []\n", ""))).unwrap();
    path.to_str().unwrap().to_owned()
}

/// `check --hardware FILE --json` (with `env`): its exit code and report.
fn check(file: &str, env: &[(&str, String)]) -> (Option<i32>, Value) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_metaplate"));
    command.args(["check", "--hardware", file, "--grid", "7x5", "--json", "--cache-dir"]).arg(cache_dir());
    for (key, value) in env {
        command.env(key, value);
    }
    let out = command.output().unwrap();
    let report = serde_json::from_str(&text(&out.stdout)).unwrap_or_else(|_| panic!("{}", text(&out.stderr)));
    (out.status.code(), report)
}

/// The checks of a report that ran and failed, with their messages.
fn failures(report: &Value) -> Vec<(String, String)> {
    report["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["passed"] == false && !c["message"].as_str().unwrap().starts_with("not run"))
        .map(|c| (c["name"].as_str().unwrap().to_owned(), c["message"].as_str().unwrap().to_owned()))
        .collect()
}

fn message<'a>(failures: &'a [(String, String)], name: &str) -> &'a str {
    failures.iter().find(|(n, _)| n == name).map(|(_, m)| m.as_str()).unwrap_or_else(|| panic!("{failures:?}"))
}

/// Faults at opening, every instrument at once: the vibrometer that does not answer (the scene's `serial_timeout`),
/// the stage that stalls homing (`stage_stall`), the interface clocked at another rate (`setup.
/// audio_device_rate_hz`, through the ALSA configuration the rig writes), and a DAQmx call that fails (the file
/// naming a device NI-DAQmx does not have). Then, on a rig whose instruments answer: the DAQ's buffer overflowing
/// (`daq_overrun`: NI-DAQmx's -200279) during the loopback, the decoder the file asks for that the unit lacks, and
/// galvo mirrors (on the stand-in's outputs) whose taught fit's residual is over its limit.
#[test]
fn each_fault_of_the_rig_fails_check_by_name() {
    let root = scratch("standin", "faults");
    let broken = scene_file(
        &root,
        "broken.toml",
        "[[faults]]\nkind = \"serial_timeout\"\nat_s = 0.0\nduration_s = 1e9\n\n[[faults]]\nkind = \"stage_stall\"\n\
         at_s = 0.0\nduration_s = 0.0\n\n[setup]\naudio_device_rate_hz = 44100.0\n",
    );
    let served = serve_scene(&broken, &root.join("broken"), &[]);
    let hardware = served.hardware();
    let other_device = std::fs::read_to_string(&hardware).unwrap().replace("device = \"Dev1\"", "device = \"Dev9\"");
    std::fs::write(&hardware, other_device).unwrap();
    let alsa = served.dir.join("asound.conf").to_str().unwrap().to_owned();
    let (code, report) = check(&hardware, &[("ALSA_CONFIG_PATH", alsa)]);
    assert_eq!(code, Some(3), "{report:#}");
    let failed = failures(&report);
    let names: Vec<&str> = failed.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["vibrometer", "daq", "audio", "aim"], "{report:#}");
    assert!(message(&failed, "vibrometer").contains("did not answer"), "{failed:?}");
    assert!(message(&failed, "daq").contains("-200220"), "{failed:?}");
    assert!(message(&failed, "audio").contains("44100"), "{failed:?}");
    assert!(message(&failed, "aim").contains("FS (stalled and stopped)"), "{failed:?}");
    drop(served);

    let overflowing =
        scene_file(&root, "overflowing.toml", "[[faults]]\nkind = \"daq_overrun\"\nat_s = 0.0\nduration_s = 1e9\n");
    let served = serve_scene(&overflowing, &root.join("overflowing"), &[]);
    let hardware = served.hardware();
    let (code, report) = check(&hardware, &[]);
    assert_eq!(code, Some(3), "{report:#}");
    let failed = failures(&report);
    assert!(message(&failed, "loopback").contains("-200279"), "{failed:?}");
    let written = std::fs::read_to_string(&hardware).unwrap();
    std::fs::write(&hardware, written.replace("[ldv]\n", "[ldv]\ndecoder = \"VD-09\"\n")).unwrap();
    let (code, report) = check(&hardware, &[]);
    assert_eq!(code, Some(3), "{report:#}");
    let failed = failures(&report);
    assert!(message(&failed, "vibrometer").contains("VD-09"), "{failed:?}");

    // Galvo mirrors on the stand-in's outputs instead of the stages, with a fit whose centre mark was taught 10 mm
    // off: refused when the rig opens, naming the residual.
    let fit = served.dir.join("galvo-fit.toml");
    let mut fit_text = "format = \"metaplate-galvo-fit\"\nversion = 1\nmodel = \"projective\"\n".to_owned();
    for (x_m, y_m, off_v) in
        [(-0.1, -0.05, 0.0), (0.1, -0.05, 0.0), (0.1, 0.05, 0.0), (-0.1, 0.05, 0.0), (0.0, 0.0, 0.4)]
    {
        let (x_v, y_v) = (40.0 * x_m + off_v, 40.0 * y_m);
        fit_text.push_str(&format!("\n[[points]]\nx_m = {x_m:?}\ny_m = {y_m:?}\nx_v = {x_v:?}\ny_v = {y_v:?}\n"));
    }
    std::fs::write(&fit, fit_text).unwrap();
    let written = std::fs::read_to_string(&hardware).unwrap();
    let (start, end) = (written.find("[aim]").unwrap(), written.find("[wiring]").unwrap());
    let galvo = "[aim]\nbackend = \"galvo\"\nfit = \"galvo-fit.toml\"\nsettle_ms = 2.0\n\n[aim.outputs]\nbackend = \"nidaqmx\"\n\
                 device = \"Dev1\"\nx_channel = \"ao0\"\ny_channel = \"ao1\"\nlibrary = \"libnidaqmx_standin.so\"\n\n";
    let galvo_file = format!("{}{galvo}{}", &written[..start], &written[end..]).replace("decoder = \"VD-09\"\n", "");
    std::fs::write(&hardware, galvo_file).unwrap();
    let (code, report) = check(&hardware, &[]);
    assert_eq!(code, Some(3), "{report:#}");
    let failed = failures(&report);
    let names: Vec<&str> = failed.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["aim"], "{report:#}");
    assert!(message(&failed, "aim").contains("aim.max_residual_mm"), "{failed:?}");
}

/// Galvo mirrors on the rig (`--aim galvo`): `aim teach --hardware` with a simulated user's keys (the lab's teacher,
/// found on the scene's mirrors in-process) drives them through the real NI-DAQmx outputs backend, the stand-in
/// library and its lab link, and writes the fit the user taught, within 0.3 mm; `check` then passes, aiming
/// through it.
#[test]
fn galvo_mirrors_are_taught_through_the_rig_and_aim_its_check() {
    use metaplate_aim::galvo::file;
    use metaplate_lab::mirrors::MirrorGeometry;
    use metaplate_lab::teacher::{NINE_MARKS_MM, teach_nine_marks};

    let root = scratch("standin", "galvo");
    let served = serve_scene("metamaterial", &root.join("rig"), &["--aim", "galvo"]);
    let hardware = served.hardware();
    let marks = root.join("marks.txt");
    std::fs::write(&marks, NINE_MARKS_MM).unwrap();
    let scene = Scene::builtin("metamaterial").unwrap();
    let (teach, keys) = teach_nine_marks(MirrorGeometry::seeded(scene.seed)).unwrap();
    let args = ["aim", "teach", "--hardware", &hardware, "--marks-file", marks.to_str().unwrap()];
    let out = crate::common::metaplate_with_input(&args, &keys);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let fit = file::read(&served.dir.join("galvo-fit.toml")).unwrap();
    // The same keys on the same mirrors, in-process and through the rig, teach the same fit.
    assert_eq!(fit.residual(), teach.fit(fit.model()).unwrap().residual());
    assert!(fit.residual().max_mm < 0.3, "{:?}", fit.residual());

    let (code, report) = check(&hardware, &[]);
    assert_eq!(code, Some(0), "{report:#}");
}
