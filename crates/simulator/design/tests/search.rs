//! `design search`'s library: the search file (values, materials, located mistakes), the grid's enumeration and
//! shards, the objectives (the paper's cell is feasible under the paper's), the trade-off front, parts and merge.

use metaplate_design::search::{self, Candidate, DesignResult, Goal, SearchSpec, Shard, mark_front};

const PAPER_OBJECTIVES: &str = "[objectives]\nmax_phase_velocity_m_s = 10.0\nover_hz = [75.0, 400.0]\n\
                                minimise = [\"added_mass_kg_m2\", \"rod_height_m\"]\n";

fn spec(text: &str) -> SearchSpec {
    SearchSpec::from_toml_str(text, "search.toml", None).unwrap()
}

#[test]
fn the_grid_enumerates_every_combination_once_and_shards_split_it() {
    let s = spec(&format!(
        "base = \"paper\"\n[vary]\nrod_height_m = {{ from = 0.02, to = 0.04, count = 3 }}\nrod_diameter_m = [0.002, 0.003]\n\
         rod_material = [\"brass\", \"steel\"]\n{PAPER_OBJECTIVES}"
    ));
    assert_eq!(s.count(), 12);
    assert_eq!(s.rod_height_m, vec![0.02, 0.03, 0.04]);
    let all: Vec<Candidate> = (0..12).map(|i| s.candidate(i).unwrap()).collect();
    assert!(s.candidate(12).is_none());
    for (i, a) in all.iter().enumerate() {
        for b in &all[i + 1..] {
            let key = |c: &Candidate| (c.rod_height_m.to_bits(), c.rod_diameter_m.to_bits(), c.rod_material.clone());
            assert_ne!(key(a), key(b), "designs {} and {} are the same", a.index, b.index);
        }
    }
    // Unvaried parameters keep the base's values; the design carries the varied ones.
    assert_eq!(all[0].lattice_constant_m, 0.008);
    let d = s.design(&all[11]);
    let metaplate_core::design::CellResonator::Rod(rod) = d.resonator else { panic!("a rod") };
    assert_eq!((rod.height_m, rod.diameter_m, rod.youngs_modulus_pa), (0.04, 0.003, 200e9));
    // Four shards: disjoint, and together the whole grid.
    let mut seen = vec![0; 12];
    for i in 0..4 {
        let shard = Shard::parse(&format!("{i}/4")).unwrap();
        (0..12).filter(|&k| shard.owns(k)).for_each(|k| seen[k] += 1);
    }
    assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    for bad in ["4/4", "1", "a/2", "0/0", "-1/3"] {
        assert!(Shard::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn mistakes_are_named_with_line_and_key() {
    let err = |text: &str| SearchSpec::from_toml_str(text, "s.toml", None).unwrap_err().to_string();
    let e = err(&format!("base = \"paper\"\n[vary]\nrod_material = [\"unobtainium\"]\n{PAPER_OBJECTIVES}"));
    assert!(e.contains("s.toml:3") && e.contains("unobtainium") && e.contains("brass"), "{e}");
    let e = err(&format!("base = \"paper\"\n[vary]\nrod_height_m = [0.02, -1.0]\n{PAPER_OBJECTIVES}"));
    assert!(e.contains("rod_height_m") && e.contains("positive"), "{e}");
    let e =
        err("base = \"paper\"\n[objectives]\nmax_phase_velocity_m_s = 10.0\nover_hz = [400.0, 75.0]\nminimise = []\n");
    assert!(e.contains("over_hz"), "{e}");
    let e = err(&format!(
        "base = \"paper\"\n[vary]\nrod_height_m = {{ from = 0.01, to = 0.05, count = 100000 }}\nrod_diameter_m = {{ from = 0.001, to = 0.003, count = 100 }}\n{PAPER_OBJECTIVES}"
    ));
    assert!(e.contains("designs") && e.contains("narrow"), "{e}");
    let e = err(&format!("base = \"paper\"\nbogus = 1\n{PAPER_OBJECTIVES}"));
    assert!(e.contains("s.toml:2") && e.contains("bogus"), "{e}");
}

/// The paper's objective (Supplementary Methods: the design was iterated until the first branch stayed under
/// 10 m/s) holds for the paper's cell, at the search's default resolution; a rod too short to resonate in band is
/// infeasible, with the reason.
#[test]
fn the_papers_cell_is_feasible_under_the_papers_objective() {
    let s = spec(&format!("base = \"paper\"\n[vary]\nrod_height_m = [0.0334563, 0.006]\n{PAPER_OBJECTIVES}"));
    let paper = search::evaluate(&s, &s.candidate(0).unwrap());
    assert!(paper.feasible, "{}", paper.reason);
    assert!(paper.max_phase_velocity_m_s < 10.0 && paper.max_phase_velocity_m_s > 3.0, "{paper:?}");
    assert!((paper.top_hz / 558.0 - 1.0).abs() < 0.05, "top {}", paper.top_hz);
    assert!((paper.mass_ratio / 10.7 - 1.0).abs() < 0.05, "mass ratio {}", paper.mass_ratio);
    let stub = search::evaluate(&s, &s.candidate(1).unwrap());
    assert!(!stub.feasible && stub.reason.contains("m/s"), "{stub:?}");
}

fn result(index: usize, feasible: bool, mass: f64, height: f64) -> DesignResult {
    DesignResult {
        candidate: Candidate {
            index,
            rod_height_m: height,
            rod_diameter_m: 0.003,
            lattice_constant_m: 0.008,
            plate_thickness_m: 0.0015,
            rod_material: "brass".into(),
            plate_material: "acrylic".into(),
        },
        feasible,
        reason: String::new(),
        top_hz: 500.0,
        max_phase_velocity_m_s: 8.0,
        added_mass_kg_m2: mass,
        mass_ratio: 1.0,
        resonator_mode_hz: 700.0,
        on_front: false,
    }
}

#[test]
fn the_front_keeps_the_feasible_designs_none_beats_on_every_goal() {
    let mut r = vec![
        result(0, true, 1.0, 0.04),  // front: lightest
        result(1, true, 2.0, 0.02),  // front: lowest
        result(2, true, 2.0, 0.04),  // beaten by 0 and 1
        result(3, false, 0.5, 0.01), // infeasible: never on the front
        result(4, true, 1.0, 0.04),  // ties 0 on both: neither beats the other
    ];
    mark_front(&mut r, &[Goal::AddedMassKgM2, Goal::RodHeightM]);
    let front: Vec<usize> = r.iter().filter(|x| x.on_front).map(|x| x.candidate.index).collect();
    assert_eq!(front, vec![0, 1, 4]);
    mark_front(&mut r, &[Goal::RodHeightM]);
    let front: Vec<usize> = r.iter().filter(|x| x.on_front).map(|x| x.candidate.index).collect();
    assert_eq!(front, vec![1]);
}

/// A coarse search (8 designs, a coarse mesh and few wave vectors: this checks the bookkeeping, not the physics)
/// run whole and as 4 shards in one process each: the merge equals the whole run's results byte for byte; a part
/// of another search and a missing shard are refused by name.
#[test]
fn shards_merged_equal_one_run_and_gaps_are_named() {
    let root =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("metaplate-search-lib-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let text = format!(
        "base = \"paper\"\n[vary]\nrod_height_m = [0.02, 0.03]\nrod_diameter_m = [0.002, 0.003]\n\
         rod_material = [\"brass\", \"aluminium\"]\n{PAPER_OBJECTIVES}[band]\nwave_vectors = 7\nmodes = 1\n\
         per_side = 1\nradial = 1\nrod_elements = 2\n"
    );
    let s = spec(&text);
    let whole = root.join("whole");
    let outcome = search::run(&s, &whole, Shard::ALL, &mut |_| {}, &|| false).unwrap();
    assert_eq!(outcome.computed, (0..8).collect::<Vec<_>>());
    let results = outcome.results.unwrap();
    assert_eq!(results.len(), 8);
    // Run again: everything is found done, nothing computed.
    let again = search::run(&s, &whole, Shard::ALL, &mut |_| {}, &|| false).unwrap();
    assert!(again.computed.is_empty() && again.resumed == 8);
    let dirs: Vec<_> = (0..4).map(|i| root.join(format!("shard{i}"))).collect();
    for (i, dir) in dirs.iter().enumerate() {
        let o = search::run(&s, dir, Shard { index: i, count: 4 }, &mut |_| {}, &|| false).unwrap();
        assert_eq!(o.computed, vec![i, i + 4]);
        assert!(o.results.is_none());
    }
    let merged = root.join("merged.parquet");
    search::merge(&s, &dirs, &merged).unwrap();
    assert_eq!(std::fs::read(&merged).unwrap(), std::fs::read(whole.join(search::RESULTS_FILE)).unwrap());
    let e = search::merge(&s, &dirs[..3], &root.join("partial.parquet")).unwrap_err().to_string();
    assert!(e.contains("2 of 8 designs are missing (first: 3, 7)"), "{e}");
    let other = spec(&text.replace("wave_vectors = 7", "wave_vectors = 8"));
    let e = search::merge(&other, &dirs, &root.join("other.parquet")).unwrap_err().to_string();
    assert!(e.contains("another search"), "{e}");
    let e = search::run(&other, &whole, Shard::ALL, &mut |_| {}, &|| false).unwrap_err().to_string();
    assert!(e.contains("another search"), "{e}");
    // A stop between designs keeps what is done, and the next run finishes the rest.
    let stopped = root.join("stopped");
    let calls = std::cell::Cell::new(0);
    let e = search::run(&s, &stopped, Shard::ALL, &mut |_| {}, &|| {
        calls.set(calls.get() + 1);
        calls.get() > 3
    })
    .unwrap_err();
    assert!(e.to_string().contains("stopped after 3 of 8"), "{e}");
    let rest = search::run(&s, &stopped, Shard::ALL, &mut |_| {}, &|| false).unwrap();
    assert_eq!((rest.resumed, rest.computed.len()), (3, 5));
    assert_eq!(
        std::fs::read(stopped.join(search::RESULTS_FILE)).unwrap(),
        std::fs::read(whole.join(search::RESULTS_FILE)).unwrap()
    );
    let _ = std::fs::remove_dir_all(&root);
}
