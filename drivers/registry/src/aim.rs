//! `[aim]` (optional): what puts the beam on a point of the plate, apart from the vibrometer.
//!
//! ```toml
//! [aim]
//! backend = "galvo"
//! fit = "galvo-fit.toml"   # written by `metaplate aim teach`; relative to the hardware file's folder
//! settle_ms = 2.0          # wait after each move, ms (>= 0)
//! max_residual_mm = 0.5    # optional: the largest residual of the fit at a taught mark, mm (default 0.5)
//!
//! [aim.outputs]            # the two analog outputs driving the X and Y mirrors
//! backend = "nidaqmx"
//! device = "Dev1"
//! x_channel = "ao0"
//! y_channel = "ao1"
//! limit_v = 10.0           # optional: the outputs' range, +/- V (default 10)
//! library = "/opt/.../libnidaqmx.so" # optional: as [daq]'s (default: $METAPLATE_NIDAQMX_LIBRARY, else NI's)
//! ```
//! Without `[aim]` the rig has no aimer and every point is refused, naming this section.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// `[aim]`: the aiming instrument.
#[derive(Debug, Clone, PartialEq)]
pub enum AimSection {
    /// `backend = "galvo"`: galvanometer mirrors on two analog outputs, through a taught fit.
    Galvo(GalvoAim),
    /// `backend = "zaber"`: Zaber XY stages under the head or the plate (`crate::ZaberAim`).
    Zaber(crate::zaber::ZaberAim),
}

impl AimSection {
    /// The backend's name in the file.
    pub fn backend(&self) -> &'static str {
        match self {
            AimSection::Galvo(_) => "galvo",
            AimSection::Zaber(_) => "zaber",
        }
    }
}

/// `[aim]` with `backend = "galvo"`.
#[derive(Debug, Clone, PartialEq)]
pub struct GalvoAim {
    /// The fit file, resolved against the hardware file's folder.
    pub fit: PathBuf,
    /// Wait after each move, ms.
    pub settle_ms: f64,
    /// The largest residual of the fit at a taught mark the rig opens with, mm: a fit beyond it (marks taught
    /// wrongly, or mirrors moved since) is refused, naming it.
    pub max_residual_mm: f64,
    /// The outputs driving the mirrors.
    pub outputs: MirrorOutputsSection,
}

/// `[aim.outputs]`: the two analog outputs of the galvo mirrors.
#[derive(Debug, Clone, PartialEq)]
pub enum MirrorOutputsSection {
    /// `backend = "nidaqmx"`: two AO channels of an NI DAQ.
    Nidaqmx(NidaqmxOutputs),
}

/// `[aim.outputs]` with `backend = "nidaqmx"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NidaqmxOutputs {
    /// NI device name (`Dev1`).
    pub device: String,
    /// The X mirror's output (`ao0`).
    pub x_channel: String,
    /// The Y mirror's output (`ao1`).
    pub y_channel: String,
    /// The outputs' range, +/- V (default 10: Thorlabs GVS drivers take +/- 10 V).
    #[serde(default = "default_limit_v")]
    pub limit_v: f64,
    /// The library to load instead of NI's, as `[daq]`'s `library` (relative: to the hardware file's folder, which
    /// parsing resolves); `None`: `$METAPLATE_NIDAQMX_LIBRARY`, else NI's.
    pub library: Option<PathBuf>,
}

fn default_limit_v() -> f64 {
    10.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGalvo {
    fit: PathBuf,
    settle_ms: f64,
    #[serde(default = "default_max_residual_mm")]
    max_residual_mm: f64,
    outputs: toml::Table,
}

/// Half a millimetre: a twentieth of the 1 cm grid pitch, beyond the 0.3 mm a taught fit lands within.
fn default_max_residual_mm() -> f64 {
    0.5
}

/// Parses `[aim]`'s keys after its `backend` (`galvo`), for the hardware file at `path`.
///
/// # Errors
/// The key in error (`aim`, `aim.settle_ms`, `aim.outputs.backend`...) and what is wrong with it.
pub(crate) fn parse_galvo(path: &Path, table: toml::Table) -> Result<AimSection, (String, String)> {
    let raw: RawGalvo = toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| ("aim".to_owned(), e.message().trim_end().to_owned()))?;
    if !(raw.settle_ms.is_finite() && raw.settle_ms >= 0.0) {
        return Err(("aim.settle_ms".into(), format!("{} is not a time >= 0 ms", raw.settle_ms)));
    }
    if !(raw.max_residual_mm.is_finite() && raw.max_residual_mm > 0.0) {
        return Err(("aim.max_residual_mm".into(), format!("{} is not a distance > 0 mm", raw.max_residual_mm)));
    }
    let mut outputs = raw.outputs;
    let backend = match outputs.remove("backend") {
        Some(toml::Value::String(name)) => name,
        _ => return Err(("aim.outputs.backend".into(), "missing or not a string: name one of nidaqmx".into())),
    };
    let outputs = match backend.as_str() {
        "nidaqmx" => {
            let mut ni: NidaqmxOutputs = toml::Value::Table(outputs)
                .try_into()
                .map_err(|e: toml::de::Error| ("aim.outputs".to_owned(), e.message().trim_end().to_owned()))?;
            ni.library =
                ni.library.map(|l| if l.is_absolute() { l } else { path.parent().unwrap_or(Path::new("")).join(l) });
            if ni.device.is_empty() || ni.device.contains('\0') {
                return Err((
                    "aim.outputs.device".into(),
                    format!("{:?} is not an NI device name (`Dev1`)", ni.device),
                ));
            }
            if !(ni.limit_v.is_finite() && ni.limit_v > 0.0) {
                return Err(("aim.outputs.limit_v".into(), format!("{} is not a positive voltage", ni.limit_v)));
            }
            MirrorOutputsSection::Nidaqmx(ni)
        }
        other => {
            return Err((
                "aim.outputs.backend".into(),
                format!("\"{other}\" is not a mirror-output backend: one of nidaqmx"),
            ));
        }
    };
    let fit = if raw.fit.is_absolute() { raw.fit } else { path.parent().unwrap_or(Path::new("")).join(raw.fit) };
    Ok(AimSection::Galvo(GalvoAim { fit, settle_ms: raw.settle_ms, max_residual_mm: raw.max_residual_mm, outputs }))
}
