//! Teaching on the mock lab's mirrors, end to end: a simulated user jogs the beam onto each mark with the keys
//! (as bytes from a terminal), the taught fit is written and read back, and a 7 x 5 scan of the plate lands within
//! 0.3 mm of every target.

use std::sync::Arc;

use metaplate_aim::galvo::teach::{Key, KeyDecoder, Teach, TeachEvent, parse_marks_mm};
use metaplate_aim::galvo::{FitModel, GalvoAimer, GalvoSettings, file};
use metaplate_core::aim::Aim;
use metaplate_core::clock::VirtualClock;
use metaplate_core::scene::Scene;
use metaplate_lab::mirrors::{MirrorGeometry, MockMirrors};
use metaplate_lab::teacher::teach_like_a_user;

fn distance_m(mirrors: &MockMirrors, mark: (f64, f64)) -> f64 {
    let (x, y) = mirrors.beam_m().expect("the beam is on");
    (x - mark.0).hypot(y - mark.1)
}

#[test]
fn a_taught_fit_lands_a_7_by_5_scan_within_0_3_mm() {
    let scene = Scene::builtin("metamaterial").expect("built-in scene");
    let geometry = MirrorGeometry::seeded(scene.seed);
    let mut mirrors = MockMirrors::new(geometry);
    // A 3 x 3 pattern of marks on the plate (inside its stadium outline), as a user writes them, mm.
    let marks =
        parse_marks_mm("# x, y in mm\n-100,-50\n0,-50\n100,-50\n-100 0\n0 0\n100 0\n-100,50\n0,50\n100,50\n", "marks")
            .expect("marks parse");
    let mut teach = Teach::new(marks, metaplate_lab::mirrors::MIRRORS_LIMIT_V).expect("valid marks");
    teach.start(&mut mirrors).expect("starts");
    let presses = teach_like_a_user(&mut teach, &mut mirrors).expect("the user teaches every mark").len();
    assert!(teach.is_finished() && teach.recorded().len() == 9, "{} recorded", teach.recorded().len());
    let fit = teach.fit(FitModel::Projective).expect("the taught marks fit");
    let residual = fit.residual();
    println!(
        "taught 9 marks in {presses} key bytes; residual rms {:.3} mm, max {:.3} mm",
        residual.rms_mm, residual.max_mm
    );
    // Each mark is taught to within the finest step (1 mV: ~0.02 mm), plus what the projective map cannot take of
    // the mirrors' pincushion (at most ~0.1 mm): well under 0.3 mm.
    assert!(residual.max_mm < 0.3, "{residual:?}");

    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("galvo-fit.toml");
    file::write(&path, &fit).expect("writes");
    let clock = Arc::new(VirtualClock::new());
    let settings = GalvoSettings { settle_s: 0.002 };
    let mut aimer =
        GalvoAimer::new(file::read(&path).expect("reads"), Box::new(mirrors.clone()), clock, settings).expect("aimer");
    let targets: Vec<(f64, f64)> =
        scene.grid.subset(7, 5).expect("7 x 5").into_iter().map(|p| scene.grid.position_m(p)).collect();
    let mut worst = (0.0, (0.0, 0.0));
    for &(x_m, y_m) in &targets {
        aimer.check_reachable(x_m, y_m).expect("the scan is within the mirrors' range");
        aimer.aim_at(x_m, y_m).expect("aims");
        let d = distance_m(&mirrors, (x_m, y_m));
        if d > worst.0 {
            worst = (d, (x_m, y_m));
        }
    }
    println!("7 x 5 scan: worst landing {:.3} mm off, at ({:.3} m, {:.3} m)", worst.0 * 1e3, worst.1.0, worst.1.1);
    assert!(worst.0 < 0.3e-3, "worst landing {:.3} mm off at {:?}", worst.0 * 1e3, worst.1);
}

#[test]
fn keys_decode_from_a_terminal_and_jog_by_the_step_within_the_limit() {
    let mut decoder = KeyDecoder::new();
    let keys: Vec<Key> = b"\x1b[A\x1bOB\x1b[C\x1b[Dx+=-\r\n\nq\x1b[Z".iter().filter_map(|&b| decoder.push(b)).collect();
    use Key::*;
    assert_eq!(keys, [Up, Down, Right, Left, Coarser, Coarser, Finer, Record, Record, Quit]);

    let mut mirrors = MockMirrors::new(MirrorGeometry::seeded(1));
    let mut teach = Teach::new(vec![(0.0, 0.0), (0.1, 0.0)], 10.0).expect("valid");
    teach.start(&mut mirrors).expect("starts");
    assert_eq!(teach.step_v(), 0.1);
    assert_eq!(
        teach.press(Right, &mut mirrors).expect("moves"),
        TeachEvent::Moved { x_v: 0.1, y_v: 0.0, clamped: false }
    );
    assert_eq!(teach.press(Coarser, &mut mirrors).expect("step"), TeachEvent::Step { step_v: 1.0 });
    assert_eq!(
        teach.press(Coarser, &mut mirrors).expect("step"),
        TeachEvent::Step { step_v: 1.0 },
        "1 V is the largest"
    );
    for _ in 0..12 {
        teach.press(Up, &mut mirrors).expect("moves");
    }
    assert_eq!(teach.volts(), (0.1, 10.0), "stopped at the outputs' limit");
    assert_eq!(mirrors.volts(), Some((0.1, 10.0)));
    assert!(matches!(teach.press(Record, &mut mirrors), Ok(TeachEvent::Recorded { mark: 0, moved_to: None, .. })));
    assert_eq!(teach.press(Quit, &mut mirrors).expect("quits"), TeachEvent::Finished);
    assert_eq!(teach.press(Left, &mut mirrors).expect("ignored"), TeachEvent::Ignored);
    assert!(teach.fit(FitModel::Projective).is_err(), "one point is too few");
    assert!(Teach::new(vec![], 10.0).is_err() && Teach::new(vec![(f64::NAN, 0.0)], 10.0).is_err());
    assert!(parse_marks_mm("1, 2\n3\n", "marks.txt").unwrap_err().to_string().contains("marks.txt:2"));
}
