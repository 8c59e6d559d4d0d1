//! `PropagationMatrices::from_dataset` against a direct FFT of the stored impulse responses; pixels snapped to the
//! same small dataset; a fingertip's reach around a pixel measured where the points are, on the grid or scattered.

#![allow(clippy::unwrap_used)] // tests may unwrap

use metaplate_control::focus::{PixelSpec, RenderOptions, render};
use metaplate_control::pixels::PointSelection;
use metaplate_control::{ControlError, PropagationMatrices};
use metaplate_dsp::fft;
use metaplate_store::{
    Dataset, DatasetMeta, DatasetWriter, GridSpec, IfExists, IrMeta, IrRecord, ScatteredPoints, SceneId,
};

const IR_LEN: usize = 64;
const FS_HZ: f64 = 24_000.0;

/// A deterministic impulse response per (point, actuator): a decaying sum of two tones with a key-dependent phase.
fn ir(point: u32, actuator: u16) -> Vec<f32> {
    (0..IR_LEN)
        .map(|i| {
            let t = i as f64 / FS_HZ;
            let phase = f64::from(point) * 0.7 + f64::from(actuator) * 1.3;
            ((-t * 900.0).exp() * ((6283.0 * t + phase).sin() + 0.5 * (21000.0 * t - phase).cos())) as f32
        })
        .collect()
}

/// The metadata of a test dataset on `grid`.
fn meta(grid: GridSpec) -> DatasetMeta {
    DatasetMeta::new("test", serde_json::Map::new(), SceneId { name: "none".into(), hash: "0".into() }, "0", 1, grid)
}

/// A 4 x 3 grid with three points measured by three actuators (0, 2, 5), written in two batches.
fn write_dataset(dir: &std::path::Path) -> Dataset {
    let grid = GridSpec { nx: 4, ny: 3, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };
    let meta = meta(grid);
    let mut writer = DatasetWriter::create(dir, meta, IfExists::Refuse).unwrap();
    for batch in [&[(0, 0), (3, 1)][..], &[(1, 2)][..]] {
        let mut records = Vec::new();
        for &(ix, iy) in batch {
            for actuator in [0, 2, 5] {
                let mut meta = IrMeta::at_grid(&grid, ix, iy, actuator, FS_HZ).unwrap();
                // Estimated errors: point 0 (-40 dB), point 7 with one poor row (-12 dB on actuator 5), point 9 none.
                meta.estimated_error_db = match (meta.point_index, actuator) {
                    (0, _) => Some(-40.0),
                    (7, 5) => Some(-12.0),
                    (7, _) => Some(-38.0),
                    _ => None,
                };
                records.push(IrRecord { ir: ir(meta.point_index, actuator), meta });
            }
        }
        writer.commit_batch(&records).unwrap();
    }
    writer.finish().unwrap();
    Dataset::open(dir).unwrap()
}

#[test]
fn g_matches_a_direct_fft_of_every_response() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = write_dataset(dir.path());
    // 24 kHz / 64 = 375 Hz bins: the band 1000 .. 5000 Hz holds bins 3 to 13.
    for fft_len in [IR_LEN, 100] {
        let g = PropagationMatrices::from_dataset_padded(&dataset, (1000.0, 5000.0), None, fft_len).unwrap();
        assert_eq!(g.points(), [0, 7, 9]);
        assert_eq!(g.actuators(), [0, 2, 5]);
        assert_eq!(g.fft_len(), fft_len);
        let first = (1000.0 * fft_len as f64 / FS_HZ).ceil() as usize;
        assert_eq!(g.bins().start, first);
        for k in 0..g.n_bins() {
            let gk = g.at_bin(k).unwrap();
            for (m, &p) in g.points().iter().enumerate() {
                for (n, &a) in g.actuators().iter().enumerate() {
                    let x: Vec<f64> = ir(p, a).iter().map(|&v| f64::from(v)).collect();
                    let want = fft::forward(&x, fft_len).unwrap()[g.bins().start + k];
                    // Same FFT on the same f64 samples (the f32 widening is exact): agreement to rounding, 1e-12 of
                    // a response whose spectrum is O(1) to O(10).
                    assert!((gk[(m, n)] - want).norm() < 1e-12, "bin {k}, point {p}, actuator {a}");
                }
            }
        }
    }
    // A point subset, in the order asked, duplicates kept.
    let g = PropagationMatrices::from_dataset(&dataset, (1000.0, 5000.0), Some(&[9, 0, 9])).unwrap();
    assert_eq!(g.points(), [9, 0, 9]);
    assert_eq!(g.at_bin(0).unwrap()[(0, 1)], g.at_bin(0).unwrap()[(2, 1)]);
}

#[test]
fn missing_points_short_ffts_and_empty_bands_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = write_dataset(dir.path());
    let band = (1000.0, 5000.0);
    assert!(matches!(
        PropagationMatrices::from_dataset(&dataset, band, Some(&[1])),
        Err(ControlError::UnknownPoint { point_index: 1 })
    ));
    assert!(matches!(
        PropagationMatrices::from_dataset_padded(&dataset, band, None, IR_LEN - 1),
        Err(ControlError::InvalidParameter { name: "fft_len", .. })
    ));
    // Between two bins (375 and 750 Hz): no bin in the band.
    assert!(matches!(
        PropagationMatrices::from_dataset(&dataset, (400.0, 700.0), None),
        Err(ControlError::EmptyBand { .. })
    ));
}

#[test]
fn a_sub_band_equals_loading_the_narrower_band() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = write_dataset(dir.path());
    let wide = PropagationMatrices::from_dataset(&dataset, (0.0, 12_000.0), None).unwrap();
    let narrow = PropagationMatrices::from_dataset(&dataset, (1000.0, 5000.0), None).unwrap();
    let cut = wide.select_band((1000.0, 5000.0)).unwrap();
    assert_eq!(cut.bins(), narrow.bins());
    assert_eq!(cut.freqs_hz(), narrow.freqs_hz());
    for k in 0..narrow.n_bins() {
        // The same FFTs of the same samples: bit-identical.
        assert_eq!(cut.at_bin(k).unwrap(), narrow.at_bin(k).unwrap(), "bin {k}");
    }
    // A band partly outside keeps the bins it shares; one sharing none is an empty band, like one between bins.
    assert_eq!(narrow.select_band((0.0, 2000.0)).unwrap().bins(), narrow.bins().start..6);
    assert!(matches!(narrow.select_band((6000.0, 9000.0)), Err(ControlError::EmptyBand { .. })));
    assert!(matches!(wide.select_band((400.0, 700.0)), Err(ControlError::EmptyBand { .. })));
    assert!(matches!(wide.select_band((700.0, 400.0)), Err(ControlError::InvalidParameter { name: "band_hz", .. })));
}

#[test]
fn pixels_snap_to_the_nearest_measured_point_or_are_refused_by_name() {
    use metaplate_control::pixels::{on_plate, snap_pixel};
    let dir = tempfile::tempdir().unwrap();
    let dataset = write_dataset(dir.path());
    // Not a built-in scene: the outline is the grid's bounds widened by half a spacing (x -2.5 to 17.5 mm, y -2.5
    // to 12.5 mm); the measured points (0, 0), (15, 5) and (5, 10) mm lie on a 5 mm lattice.
    let outline = on_plate(&dataset);
    assert_eq!(snap_pixel(&dataset, 0.001, 0.0, &outline).unwrap(), 0);
    assert_eq!(snap_pixel(&dataset, 0.0149, 0.0051, &outline).unwrap(), 7);
    for (x, y) in [(0.05, 0.0), (f64::NAN, 0.0), (0.0, -0.003)] {
        let err = snap_pixel(&dataset, x, y, &outline).unwrap_err();
        assert!(matches!(err, ControlError::PixelOffPlate { .. }), "({x}, {y}): {err}");
    }
    let err = snap_pixel(&dataset, 0.015, 0.01, &outline).unwrap_err();
    let ControlError::PixelInGap { distance_mm, nearest_m, step_mm, .. } = err else { panic!("{err}") };
    assert!((distance_mm - 5.0).abs() < 1e-9 && step_mm == (5.0, 5.0), "{distance_mm} {step_mm:?}");
    assert!((nearest_m.0 - 0.015).abs() < 1e-12 && (nearest_m.1 - 0.005).abs() < 1e-12, "{nearest_m:?}");
    assert!(err.to_string().contains("pixel (0.015, 0.01) is 5.0 mm from the nearest measured point"), "{err}");
}

#[test]
fn points_are_selected_by_their_worst_rows_estimated_error() {
    let dir = tempfile::tempdir().unwrap();
    let dataset = write_dataset(dir.path());
    // -20 dB: point 7's worst row (-12 dB) is out; point 9 has no estimate and is kept, counted as such.
    let s = PointSelection::by_estimated_error(&dataset, -20.0).unwrap();
    assert_eq!(s.kept, [0, 9]);
    assert_eq!(s.excluded, [(7, -12.0)]);
    assert_eq!(s.without_estimate, 1);
    // The limit is inclusive, and the extremes keep everything or refuse to keep nothing.
    assert_eq!(PointSelection::by_estimated_error(&dataset, -12.0).unwrap().kept, [0, 7, 9]);
    assert_eq!(PointSelection::by_estimated_error(&dataset, f64::INFINITY).unwrap().excluded, []);
    assert_eq!(PointSelection::by_estimated_error(&dataset, f64::NEG_INFINITY).unwrap().kept, [9]);
    assert!(matches!(
        PointSelection::by_estimated_error(&dataset, f64::NAN),
        Err(ControlError::InvalidParameter { .. })
    ));
    // A pixel on an excluded point is refused by name; elsewhere it passes.
    let err = s.check_pixel(0.015, 0.005, 7).unwrap_err();
    assert!(matches!(err, ControlError::PixelExcluded { point_index: 7, .. }), "{err}");
    assert!(err.to_string().contains("-12.0 dB") && err.to_string().contains("-20.0 dB"), "{err}");
    assert!(s.check_pixel(0.0, 0.0, 0).is_ok());
    // G over the kept points only.
    let g = PropagationMatrices::from_dataset(&dataset, (1000.0, 5000.0), Some(&s.kept)).unwrap();
    assert_eq!(g.points(), [0, 9]);
}

/// The dataset of [`write_dataset`] written again with its three points (0, 7, 9) as scattered points 0, 1, 2, 0.1 m
/// apart on a line: the same responses, positions that are not the grid's.
fn write_scattered(dir: &std::path::Path, from: &Dataset) -> Dataset {
    let positions_m = vec![(0.0, 0.0), (0.1, 0.0), (0.2, 0.0)];
    let grid = GridSpec { nx: 3, ny: 1, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };
    let meta = meta(grid).with_scattered(ScatteredPoints { positions_m: positions_m.clone(), frame: "a test".into() });
    let mut writer = DatasetWriter::create(dir, meta, IfExists::Refuse).unwrap();
    let records: Vec<IrRecord> = from
        .rows()
        .iter()
        .map(|m| {
            let index = [0, 7, 9].iter().position(|&p| p == m.point_index).unwrap();
            let mut meta = *m;
            (meta.point_index, meta.ix, meta.iy) = (index as u32, index as u32, 0);
            (meta.x_m, meta.y_m) = positions_m[index];
            IrRecord { ir: from.ir(m.point_index, m.actuator).unwrap().to_vec(), meta }
        })
        .collect();
    writer.commit_batch(&records).unwrap();
    writer.finish().unwrap();
    Dataset::open(dir).unwrap()
}

#[test]
fn a_fingertips_reach_is_measured_where_the_points_are() {
    let dir = tempfile::tempdir().unwrap();
    let on_grid = write_dataset(&dir.path().join("grid"));
    let scattered = write_scattered(&dir.path().join("scattered"), &on_grid);
    let options = RenderOptions { band_lo_hz: 1000.0, band_hi_hz: 5000.0, ..RenderOptions::default() };
    // A null at the first point, an impulse at the second: beside the null the field is larger than at it.
    let render = |dataset: &Dataset, at: [(f64, f64); 2]| {
        let specs: Vec<PixelSpec> = [format!("{},{}:null", at[0].0, at[0].1), format!("{},{}", at[1].0, at[1].1)]
            .map(|t| t.parse().unwrap())
            .into();
        let rendered = render(dataset, &specs, None, &options).unwrap();
        let own: Vec<f64> = rendered
            .field_at_pixels()
            .unwrap()
            .iter()
            .map(|v| v.iter().fold(0.0, |m: f64, x| m.max(x.abs())))
            .collect();
        (rendered, own)
    };
    // On the grid, point 9 (5, 10 mm) is 11.2 mm from point 0: within a 12 mm reach of the null.
    let (rendered, own) = render(&on_grid, [(0.0, 0.0), (0.015, 0.005)]);
    let within = rendered.peaks_within(&on_grid.manifest().meta, 0.012).unwrap();
    assert!(within[0] > own[0], "the reach of the null takes in its neighbour: {within:?} vs {own:?}");
    // Scattered 0.1 m apart, the null's reach holds itself alone (the grid index would put a neighbour 5 mm away).
    let (rendered, own) = render(&scattered, [(0.0, 0.0), (0.1, 0.0)]);
    let within = rendered.peaks_within(&scattered.manifest().meta, 0.012).unwrap();
    assert_eq!(within, own, "each pixel's reach is its own point");
    // A reach over every point takes the largest field anywhere, on both.
    let all = rendered.peaks_within(&scattered.manifest().meta, 1.0).unwrap();
    assert!(all.iter().all(|&v| v >= own[0].max(own[1])), "{all:?}");
}
