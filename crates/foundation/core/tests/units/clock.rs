use metaplate_core::clock::*;
use std::sync::Arc;

#[test]
fn virtual_clock_advances_without_sleeping() {
    let clock = VirtualClock::new();
    let wall = std::time::Instant::now();
    // A 3 s sweep, 1225 points x 8 actuators x 5 repeats: 40.8 simulated hours.
    for _ in 0..1225 * 8 * 5 {
        clock.sleep_s(3.0);
    }
    // Exact: 3 and every multiple of it up to 1.5e5 are integers, exactly representable in f64.
    assert_eq!(clock.now_s(), 3.0 * 1225.0 * 8.0 * 5.0);
    // Generous bound for a loaded 2-core machine; sleeping would take 41 hours.
    assert!(wall.elapsed().as_secs_f64() < 1.0);
}

#[test]
fn virtual_clock_refuses_bad_steps() {
    let clock = VirtualClock::new();
    assert_eq!(clock.advance(0.5), 0.5);
    for bad in [-1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0] {
        assert_eq!(clock.advance(bad), 0.5, "step {bad}");
    }
    // The largest finite step still leaves a finite time; a second one would overflow and is refused.
    assert_eq!(clock.advance(f64::MAX), f64::MAX);
    assert_eq!(clock.advance(f64::MAX), f64::MAX);
    assert!(clock.now_s().is_finite());
}

#[test]
fn virtual_clock_is_shared_between_threads() {
    let clock = Arc::new(VirtualClock::new());
    let threads: Vec<_> = (0..4)
        .map(|_| {
            let clock = Arc::clone(&clock);
            std::thread::spawn(move || (0..1000).for_each(|_| clock.sleep_s(0.25)))
        })
        .collect();
    for thread in threads {
        thread.join().unwrap();
    }
    // Exact: 0.25 steps sum exactly in f64; no advance may be lost to a race.
    assert_eq!(clock.now_s(), 1000.0);
}

#[test]
fn real_clock_sleeps_and_ignores_bad_durations() {
    let clock = RealClock::new();
    let t0 = clock.now_s();
    clock.sleep_s(0.02);
    let slept = clock.now_s() - t0;
    // At least the requested time (the OS never wakes early); the upper bound only catches a sleep in ms
    // mistaken for s, with room for a loaded machine.
    assert!((0.02..1.0).contains(&slept), "slept {slept} s");
    let t1 = clock.now_s();
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        clock.sleep_s(bad);
    }
    assert!(clock.now_s() - t1 < 0.5);
}
