//! The fit file: the taught points and the model, written by `metaplate aim teach`, read by the aimer.
//!
//! ```toml
//! format = "metaplate-galvo-fit"
//! version = 1
//! model = "projective"          # or "polynomial2"
//!
//! [[points]]                    # one per taught mark, in teaching order
//! x_m = -0.1                    # the mark on the plate, m
//! y_m = -0.05
//! x_v = -4.213                  # the mirror voltages that put the beam on it, V
//! y_v = -2.107
//! ```
//! The file holds what was taught, not the map's coefficients: reading it fits the map again (the same points
//! give the same map), so the file cannot hold a map that disagrees with its points, and the residual is always
//! the points' own. A comment records the residual at teaching, for a person reading the file.

use std::path::Path;

use metaplate_core::toml_locate::DocIndex;

use super::{FitModel, GalvoError, GalvoFit, TaughtPoint};

/// The `format` key's value.
pub const FORMAT: &str = "metaplate-galvo-fit";

/// The version this build writes and reads.
pub const VERSION: u32 = 1;

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct FitFile {
    format: String,
    version: u32,
    model: FitModel,
    points: Vec<TaughtPoint>,
}

/// The fit as the file's text.
pub fn to_toml(fit: &GalvoFit) -> String {
    let r = fit.residual();
    let mut text = format!(
        "# Galvo mirrors' plate-to-volts map, written by `metaplate aim teach`: the taught points; the map is fitted\n\
         # again from them when read. Residual at teaching: rms {:.3} mm, max {:.3} mm (point {}).\n\
         format = \"{FORMAT}\"\nversion = {VERSION}\nmodel = \"{}\"\n",
        r.rms_mm,
        r.max_mm,
        r.worst_point,
        fit.model().name()
    );
    for p in fit.points() {
        // `{:?}` prints an f64 exactly (shortest round-trip form), so the points read back bit for bit.
        text.push_str(&format!(
            "\n[[points]]\nx_m = {:?}\ny_m = {:?}\nx_v = {:?}\ny_v = {:?}\n",
            p.x_m, p.y_m, p.x_v, p.y_v
        ));
    }
    text
}

/// Parses a fit file's text (`origin` names it in errors) and fits its map.
///
/// # Errors
/// [`GalvoError::File`] naming the file, line and key: not TOML, an unknown or missing key, another format or
/// version, or points that do not determine the map (too few, duplicated, collinear).
pub fn from_toml_str(text: &str, origin: &str) -> Result<GalvoFit, GalvoError> {
    let doc = DocIndex::parse(text, origin).map_err(GalvoError::File)?;
    let file: FitFile = toml::from_str(text).map_err(|e| GalvoError::File(doc.schema_error(&e)))?;
    let invalid = |key: &str, message: String| GalvoError::File(doc.invalid(key.to_owned(), message));
    if file.format != FORMAT {
        return Err(invalid("format", format!("is \"{}\", expected \"{FORMAT}\"", file.format)));
    }
    if file.version != VERSION {
        return Err(invalid("version", format!("{} is not one this build reads (it reads {VERSION})", file.version)));
    }
    GalvoFit::fit(file.model, &file.points).map_err(|e| {
        let key = match &e {
            GalvoError::InvalidPoint { index, .. } => format!("points[{index}]"),
            GalvoError::Duplicate { second, .. } => format!("points[{second}]"),
            _ => "points".to_owned(),
        };
        invalid(&key, e.to_string())
    })
}

/// Writes `fit` to `path` (replacing it through a temporary file beside it, so a crash leaves the old file whole).
///
/// # Errors
/// [`GalvoError::Io`].
pub fn write(path: &Path, fit: &GalvoFit) -> Result<(), GalvoError> {
    let io = |source| GalvoError::Io { path: path.to_owned(), source };
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    std::fs::write(&tmp, to_toml(fit)).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Reads and fits the file at `path`.
///
/// # Errors
/// [`GalvoError::Io`] when it cannot be read; as [`from_toml_str`].
pub fn read(path: &Path) -> Result<GalvoFit, GalvoError> {
    let text = std::fs::read_to_string(path).map_err(|source| GalvoError::Io { path: path.to_owned(), source })?;
    from_toml_str(&text, &path.display().to_string())
}
