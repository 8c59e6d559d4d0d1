//! The fit file: written and read back to the same map; refused with the file, line and key named.

use metaplate_aim::GalvoError;
use metaplate_aim::galvo::{FitModel, GalvoFit, TaughtPoint, file};

fn fit() -> GalvoFit {
    let points: Vec<TaughtPoint> = [
        (-0.1, -0.05, -4.9, -2.6),
        (0.1, -0.05, 5.2, -2.4),
        (0.1, 0.05, 5.0, 2.5),
        (-0.1, 0.05, -5.1, 2.45),
        (0.0, 0.0, 0.05, -0.02),
    ]
    .iter()
    .map(|&(x_m, y_m, x_v, y_v)| TaughtPoint { x_m, y_m, x_v, y_v })
    .collect();
    GalvoFit::fit(FitModel::Projective, &points).expect("fits")
}

#[test]
fn a_written_file_reads_back_to_the_same_fit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("galvo-fit.toml");
    let fit = fit();
    file::write(&path, &fit).expect("writes");
    let read = file::read(&path).expect("reads");
    assert_eq!(read, fit, "the same points bit for bit, so the same map");
    let text = std::fs::read_to_string(&path).expect("text");
    assert!(text.contains("rms") && text.contains("format = \"metaplate-galvo-fit\""), "{text}");
}

#[test]
fn a_bad_file_names_the_file_line_and_key() {
    let good = file::to_toml(&fit());
    let cases = [
        (good.replace("version = 1", "version = 2"), ":4:1: version: 2 is not one this build reads"),
        (good.replace("metaplate-galvo-fit", "something-else"), "format: is \"something-else\""),
        (good.replace("model = \"projective\"", "model = \"cubic\""), "model"),
        (good.replacen("x_v =", "x_volts =", 1), "x_volts"),
        (good.replacen("y_m = 0.05", "y_m = -0.05", 2), "points[3]: taught points 0 and 3 coincide"),
        (good.replace("[[points]]", "[points]"), ":13:2: duplicate key"),
    ];
    for (text, expected) in cases {
        let err = file::from_toml_str(&text, "rig/galvo-fit.toml").unwrap_err();
        let message = err.to_string();
        assert!(matches!(err, GalvoError::File(_)), "{message}");
        assert!(message.contains("rig/galvo-fit.toml:") && message.contains(expected), "{message} lacks {expected}");
    }
    let err = file::read(std::path::Path::new("/nonexistent/galvo-fit.toml")).unwrap_err();
    assert!(matches!(err, GalvoError::Io { .. }) && err.to_string().contains("/nonexistent/galvo-fit.toml"), "{err}");
}
