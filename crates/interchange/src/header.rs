//! The dataset 151 (header) metaplate writes at the top of an export: what belongs to the dataset as a whole and
//! does not fit the 80-column ID lines of its responses: the `ir` unit in full, and the content hash of the
//! calibration a scan was measured through. An import of the file restores both, so that a scan exported and
//! imported again still plays through its calibration.
//!
//! | record | field | metaplate writes |
//! |---|---|---|
//! | 1 | model file name | the dataset's directory name |
//! | 2 | model file description | the dataset's `ir` unit (`m/s per full-scale drive, through the calibration's inverse filters`) |
//! | 3 | program which created the database | `metaplate`, then ` cal=HEX` for a scan through a calibration: the calibration's content hash `sha256:HEX` without its prefix (78 columns) |
//! | 4, 5, 7 | dates and times | `NONE`: an export of a dataset is the same bytes whenever it is written |
//! | 6 | program which wrote the file | `metaplate VERSION` |
//!
//! A header whose record 3 is not metaplate's (another tool's) is skipped, as every dataset an import does not use.

use std::path::Path;

use metaplate_store::DatasetMeta;
use metaplate_uff::Header151;

use crate::IdLines;

/// The unit an import restores from metaplate's header, when the responses are velocity over "full scale": the
/// scans' units begin so (the responses' records carry only "full scale").
const SCAN_UNIT_PREFIX: &str = "m/s per full-scale drive";

/// The dataset 151 an export of the dataset `meta`, in the directory `data`, begins with.
pub(crate) fn for_dataset(data: &Path, meta: &DatasetMeta) -> Header151 {
    let name = data.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let db_program = match calibration_of(meta) {
        Some(hash) => format!("metaplate cal={hash}"),
        None => "metaplate".to_owned(),
    };
    let none = || ["NONE".to_owned(), "NONE".to_owned()];
    Header151 {
        model_name: text(&name),
        description: text(meta.description.as_ref().map_or("", |d| d.ir_unit.as_str())),
        db_program,
        db_created: none(),
        db_saved: none(),
        program: format!("metaplate {}", env!("CARGO_PKG_VERSION")),
        file_written: none(),
    }
}

/// What an import takes from metaplate's header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Restored {
    /// The `ir` unit as the dataset stated it (record 2).
    pub unit: String,
    /// The content hash of the calibration the scan was measured through, `sha256:` and record 3's `cal=` (64 hex
    /// digits).
    pub calibration: Option<String>,
}

/// What `header` restores, or `None` for a header another tool wrote.
pub(crate) fn restored(header: &Header151) -> Option<Restored> {
    let ours = header.db_program == "metaplate" || header.db_program.starts_with("metaplate ");
    if !ours {
        return None;
    }
    let calibration = IdLines::value(&header.db_program, "cal").filter(|h| is_hex256(h)).map(|h| format!("sha256:{h}"));
    Some(Restored { unit: header.description.clone(), calibration })
}

impl Restored {
    /// The unit of an import whose responses are velocity over a denominator labelled `label` (`None`: not over
    /// an "other" denominator): the header's, where the records say "full scale" and the header a scan's unit.
    pub(crate) fn unit_over(&self, label: Option<&str>) -> Option<&str> {
        (label == Some("full scale") && self.unit.starts_with(SCAN_UNIT_PREFIX)).then_some(self.unit.as_str())
    }
}

/// The hex digits of the calibration hash a dataset's configuration names (a scan through a calibration:
/// `sha256:HEX`), if it is one.
fn calibration_of(meta: &DatasetMeta) -> Option<&str> {
    let hash = meta.config.get("calibration").and_then(|v| v.as_str())?;
    hash.strip_prefix("sha256:").filter(|h| is_hex256(h))
}

/// 64 hex digits (a SHA-256 digest).
fn is_hex256(text: &str) -> bool {
    text.len() == 64 && text.bytes().all(|b| b.is_ascii_hexdigit())
}

/// `text` as a record of 80 printable Latin-1 characters ([`metaplate_uff::printable`]), and never a lone `-1` (a
/// line that reads as the dataset's closing delimiter, which the encoder refuses).
fn text(text: &str) -> String {
    let mut out = metaplate_uff::printable(text, 80);
    if out.trim() == "-1" {
        out = out.replace('-', "_");
    }
    out
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use metaplate_core::grid::GridSpec;
    use metaplate_store::{DatasetDescription, SceneId};

    use super::*;

    fn meta(unit: &str, calibration: Option<&str>) -> DatasetMeta {
        let mut config = serde_json::Map::new();
        if let Some(hash) = calibration {
            config.insert("calibration".into(), hash.into());
        }
        let scene = SceneId { name: "metamaterial".into(), hash: "abc".into() };
        DatasetMeta::new("scan", config, scene, "0", 7, GridSpec::centred(3, 2, 0.08))
            .with_description(DatasetDescription { ir_unit: unit.into(), pre_samples: 0 })
    }

    #[test]
    fn a_scan_through_a_calibration_restores_its_unit_and_hash() {
        let hex = "0123456789abcdef".repeat(4);
        let hash = format!("sha256:{hex}");
        let unit = "m/s per full-scale drive, through the calibration's inverse filters";
        let header = for_dataset(Path::new("/data/scan-3x2"), &meta(unit, Some(&hash)));
        assert_eq!(header.model_name, "scan-3x2");
        assert_eq!(header.db_program, format!("metaplate cal={hex}"));
        assert_eq!(header.db_program.len(), 78);
        let restored = restored(&header).unwrap();
        assert_eq!(restored, Restored { unit: unit.into(), calibration: Some(hash) });
        assert_eq!(restored.unit_over(Some("full scale")), Some(unit));
        // Other records than "full scale", or a unit that is no scan's, are read from the responses.
        assert_eq!(restored.unit_over(Some("V")), None);
        assert_eq!(restored.unit_over(None), None);
        let ground_truth = restored_of(&for_dataset(Path::new("g"), &meta("m/s/N", None)));
        assert_eq!((ground_truth.unit_over(Some("full scale")), &ground_truth.calibration), (None, &None));
    }

    fn restored_of(header: &Header151) -> Restored {
        restored(header).unwrap()
    }

    #[test]
    fn another_tools_header_or_a_malformed_hash_restores_nothing() {
        let unhashed = format!("md5:{}", "0".repeat(64));
        let mut header = for_dataset(Path::new("-1"), &meta("m/s per full-scale drive", Some(&unhashed)));
        assert_eq!(header.model_name, "_1", "a name that would read as a delimiter");
        assert_eq!(header.db_program, "metaplate", "no hash written for a configuration's malformed one");
        header.db_program = format!("metaplate cal={}", "g".repeat(64));
        assert_eq!(restored(&header).unwrap().calibration, None);
        for program in ["LMS Test.Lab Rev project-15A", "NONE", "metaplatex cal=00"] {
            header.db_program = program.into();
            assert_eq!(restored(&header), None, "{program}");
        }
        assert_eq!(text(&"é€".repeat(60)).chars().count(), 80);
        assert!(text("a€b").contains("a_b"));
    }
}
