//! Random datasets round-trip exactly: every record, every IR bit, and the manifest (including its float fields).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use metaplate_store::{Dataset, DatasetMeta, DatasetWriter, GridSpec, IfExists, IrMeta, IrRecord, SceneId, Status};
use proptest::prelude::*;

/// Any finite f32, from uniformly random bits (so subnormals, -0.0 and extreme exponents all occur).
fn finite_f32() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits).prop_filter("finite", |v| v.is_finite())
}

/// A finite f64 of any magnitude, from random bits.
fn finite_f64() -> impl Strategy<Value = f64> {
    any::<u64>().prop_map(f64::from_bits).prop_filter("finite", |v| v.is_finite())
}

/// Quality fields, each present or absent.
fn quality() -> impl Strategy<Value = (Option<f64>, Option<Status>, Option<u32>, Option<i64>)> {
    (
        proptest::option::of(finite_f64()),
        proptest::option::of(proptest::sample::select(Status::ALL.to_vec())),
        proptest::option::of(any::<u32>()),
        proptest::option::of(any::<i64>()),
    )
}

/// A grid, a set of distinct (point, actuator) records on it with one IR length, and cut points splitting them
/// into batches.
fn dataset() -> impl Strategy<Value = (GridSpec, f64, Vec<IrRecord>, Vec<usize>)> {
    let grid = (1usize..6, 1usize..6, 1e-4f64..0.1, -1.0f64..1.0, -1.0f64..1.0)
        .prop_map(|(nx, ny, spacing_m, ox, oy)| GridSpec { nx, ny, spacing_m, origin_x_m: ox, origin_y_m: oy });
    (grid, 1usize..48, prop_oneof![Just(24_000.0), 1.0f64..1e6]).prop_flat_map(|(grid, ir_len, rate)| {
        let keys = proptest::collection::btree_set((0..grid.nx as u32, 0..grid.ny as u32, 0u16..12), 1..24);
        let records = keys.prop_flat_map(move |keys| {
            let n = keys.len();
            let irs = proptest::collection::vec(proptest::collection::vec(finite_f32(), ir_len), n);
            let qualities = proptest::collection::vec(quality(), n);
            let offsets = proptest::collection::vec((finite_f64(), finite_f64()), n);
            (Just(keys), irs, qualities, offsets)
        });
        let cuts = proptest::collection::vec(0usize..24, 0..4);
        (Just(grid), Just(rate), records, cuts).prop_map(move |(grid, rate, (keys, irs, qualities, xy), cuts)| {
            let records = keys
                .into_iter()
                .zip(irs)
                .zip(qualities)
                .zip(xy)
                .map(|((((ix, iy, actuator), ir), (snr_db, status, retries, at)), (x_m, y_m))| {
                    let mut meta = IrMeta::at_grid(&grid, ix, iy, actuator, rate).unwrap();
                    // Positions need not be the nominal ones (a measured beam position); any finite value is valid.
                    (meta.x_m, meta.y_m) = (x_m, y_m);
                    (meta.snr_db, meta.status, meta.retries, meta.measured_at_unix_us) = (snr_db, status, retries, at);
                    // The error estimate rides with the SNR (null with it), so both nulls and values round-trip.
                    meta.estimated_error_db = snr_db.map(|s| -s);
                    IrRecord { meta, ir }
                })
                .collect();
            (grid, rate, records, cuts)
        })
    })
}

proptest! {
    // Each case writes and fsyncs a few files: 48 cases keep this under a few seconds.
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn random_datasets_round_trip_exactly(
        (grid, rate, records, cuts) in dataset(),
        seed in any::<u64>(),
        config_value in finite_f64(),
    ) {
        let config = serde_json::json!({"x": config_value, "nested": {"b": [config_value, 1], "a": null}});
        let meta = DatasetMeta::new(
            "proptest",
            config.as_object().cloned().unwrap_or_default(),
            SceneId { name: "random".into(), hash: "none".into() },
            "0",
            seed,
            grid,
        );
        let dir = tempfile::tempdir().unwrap();
        let mut writer = DatasetWriter::create(dir.path(), meta, IfExists::Refuse).unwrap();
        let mut bounds: Vec<usize> = cuts.into_iter().map(|c| c % records.len()).filter(|&c| c > 0).collect();
        bounds.extend([0, records.len()]);
        bounds.sort_unstable();
        bounds.dedup();
        for w in bounds.windows(2) {
            writer.commit_batch(&records[w[0]..w[1]]).unwrap();
        }
        let manifest = writer.finish().unwrap();

        let dataset = Dataset::open(dir.path()).unwrap();
        // The manifest (floats in the grid and config included) comes back identical, so its hash verifies.
        prop_assert_eq!(dataset.manifest(), &manifest);
        prop_assert_eq!(dataset.sample_rate_hz().to_bits(), rate.to_bits());
        prop_assert_eq!(dataset.len(), records.len());
        for (row, record) in records.iter().enumerate() {
            prop_assert_eq!(&dataset.rows()[row], &record.meta);
            let back = dataset.ir(record.meta.point_index, record.meta.actuator).unwrap();
            let bits = |ir: &[f32]| ir.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            prop_assert_eq!(bits(back), bits(&record.ir));
        }
    }
}
