//! The ID lines of metaplate's records: what an import needs to rebuild an exported dataset exactly.

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::SceneId;
use metaplate_store::{DatasetMeta, IrMeta, Status};

/// The ID lines of metaplate's records: `metaplate KEY=VALUE ...`, values without spaces.
///
/// 1. `metaplate point=P actuator=A [measured_at_us=T]`: the dataset key, and the row's measurement time (µs since
///    the Unix epoch) when it has one (up to 0.6 it was on line 4, where a long SNR cut it: both are read);
/// 2. `metaplate grid=NXxNY spacing_m=H origin_m=X0,Y0`: the dataset's grid (`metaplate scattered=N` for points
///    on no lattice, which an import places again by their nodes);
/// 3. `metaplate scene=NAME scene_hash=HASH`: the scene id;
/// 4. `metaplate status=S snr_db=X retries=R`: the row's quality (absent keys: not recorded);
/// 5. `metaplate recipe=R seed=S [estimated_error_db=E]`: where the dataset came from, and the row's estimated error
///    when it has one (line 4 is full).
///
/// Spaces inside a value are written `_`; a line is cut at 80 columns. A line another tool wrote parses as `None`.
pub struct IdLines;

/// The parts of the ID lines shared by every row of a dataset.
pub(crate) struct SharedIds {
    grid: String,
    scene: String,
    source: String,
}

impl SharedIds {
    /// The shared lines of the dataset described by `meta`.
    pub(crate) fn new(meta: &DatasetMeta) -> Self {
        Self {
            grid: match &meta.scattered {
                // No grid to give: an import places scattered points again by their nodes.
                Some(s) => format!("metaplate scattered={}", s.positions_m.len()),
                None => IdLines::grid(&meta.grid),
            },
            scene: cut(format!("metaplate scene={} scene_hash={}", word(&meta.scene.name), word(&meta.scene.hash))),
            source: cut(format!("metaplate recipe={} seed={}", word(&meta.recipe), meta.seed)),
        }
    }

    /// The five ID lines of `row`.
    pub(crate) fn for_row(&self, row: &IrMeta) -> [String; 5] {
        let mut quality = String::from("metaplate");
        if let Some(status) = row.status {
            quality.push_str(&format!(" status={}", status.as_str()));
        }
        if let Some(snr_db) = row.snr_db {
            quality.push_str(&format!(" snr_db={snr_db}"));
        }
        if let Some(retries) = row.retries {
            quality.push_str(&format!(" retries={retries}"));
        }
        let source = match row.estimated_error_db {
            Some(e) => cut(format!("{} estimated_error_db={e}", self.source)),
            None => self.source.clone(),
        };
        [
            // At most 77 columns: `u32`, `u16` and `i64` written in full.
            match row.measured_at_unix_us {
                Some(t) => format!("metaplate point={} actuator={} measured_at_us={t}", row.point_index, row.actuator),
                None => format!("metaplate point={} actuator={}", row.point_index, row.actuator),
            },
            self.grid.clone(),
            self.scene.clone(),
            cut(quality),
            source,
        ]
    }
}

impl IdLines {
    /// ID line 2 for `grid`.
    fn grid(g: &GridSpec) -> String {
        cut(format!(
            "metaplate grid={}x{} spacing_m={} origin_m={},{}",
            g.nx, g.ny, g.spacing_m, g.origin_x_m, g.origin_y_m
        ))
    }

    /// The `KEY=VALUE` pairs of a metaplate ID line, or `None` for a line metaplate did not write.
    pub fn pairs(line: &str) -> Option<Vec<(&str, &str)>> {
        let rest = line.trim().strip_prefix("metaplate ")?;
        Some(rest.split_whitespace().filter_map(|w| w.split_once('=')).collect())
    }

    /// The value of `key` in a metaplate ID line.
    pub fn value<'a>(line: &'a str, key: &str) -> Option<&'a str> {
        Self::pairs(line)?.into_iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// The grid of ID line 2, if it is a metaplate one (and a valid grid).
    pub fn parse_grid(line: &str) -> Option<GridSpec> {
        let (nx, ny) = Self::value(line, "grid")?.split_once('x')?;
        let (x0, y0) = Self::value(line, "origin_m")?.split_once(',')?;
        let grid = GridSpec {
            nx: nx.parse().ok()?,
            ny: ny.parse().ok()?,
            spacing_m: Self::value(line, "spacing_m")?.parse().ok()?,
            origin_x_m: x0.parse().ok()?,
            origin_y_m: y0.parse().ok()?,
        };
        grid.validate().ok().map(|()| grid)
    }

    /// The (point, actuator) of ID line 1, if it is a metaplate one.
    pub fn parse_key(line: &str) -> Option<(u32, u16)> {
        Some((Self::value(line, "point")?.parse().ok()?, Self::value(line, "actuator")?.parse().ok()?))
    }

    /// The scene id of ID line 3, if it is a metaplate one.
    pub fn parse_scene(line: &str) -> Option<SceneId> {
        Some(SceneId {
            name: Self::value(line, "scene")?.to_owned(),
            hash: Self::value(line, "scene_hash")?.to_owned(),
        })
    }

    /// The row's estimated error of ID line 5, dB, if it has one (finite).
    pub fn parse_estimated_error(line: &str) -> Option<f64> {
        Self::value(line, "estimated_error_db").and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite())
    }

    /// The row's measurement time of ID line 1, µs since the Unix epoch, if it has one.
    pub fn parse_measured_at(line: &str) -> Option<i64> {
        Self::value(line, "measured_at_us").and_then(|v| v.parse().ok())
    }

    /// The row quality of ID line 4: status, SNR (dB), retries, and the measurement time (µs since the Unix epoch)
    /// that files written before 0.7 put there; each `None` when absent or unreadable.
    pub fn parse_quality(line: &str) -> (Option<Status>, Option<f64>, Option<u32>, Option<i64>) {
        let status = Self::value(line, "status").and_then(Status::parse);
        let snr_db = Self::value(line, "snr_db").and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite());
        let retries = Self::value(line, "retries").and_then(|v| v.parse().ok());
        let measured_at = Self::value(line, "measured_at_us").and_then(|v| v.parse().ok());
        (status, snr_db, retries, measured_at)
    }
}

/// `text` with spaces (and anything not printable ASCII) as `_` (one word of an ID line).
fn word(text: &str) -> String {
    text.chars().map(|c| if c.is_ascii_graphic() { c } else { '_' }).collect()
}

/// `line` cut to the 80 columns of an ID line.
fn cut(mut line: String) -> String {
    line.truncate(80);
    line
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use metaplate_store::{IrMeta, SceneId};

    use super::*;

    fn meta(recipe: &str, scene: &str) -> DatasetMeta {
        let grid = GridSpec::centred(13, 7, 0.005);
        let scene = SceneId { name: scene.into(), hash: "abc123".into() };
        DatasetMeta::new(recipe, serde_json::Map::new(), scene, "0", 42, grid)
    }

    #[test]
    fn the_lines_written_for_a_row_parse_back_to_its_key_grid_scene_and_quality() {
        let meta = meta("scan", "metamaterial");
        let mut row = IrMeta::at_grid(&meta.grid, 4, 2, 3, 24_000.0).unwrap();
        (row.status, row.snr_db, row.retries, row.measured_at_unix_us) =
            (Some(Status::Valid), Some(61.25), Some(2), Some(1_700_000_000_123_456));
        row.estimated_error_db = Some(-31.5);
        let lines = SharedIds::new(&meta).for_row(&row);
        assert_eq!(IdLines::parse_key(&lines[0]), Some((row.point_index, 3)));
        assert_eq!(IdLines::parse_grid(&lines[1]), Some(meta.grid));
        assert_eq!(IdLines::parse_scene(&lines[2]), Some(meta.scene.clone()));
        assert_eq!(IdLines::parse_quality(&lines[3]), (Some(Status::Valid), Some(61.25), Some(2), None));
        assert_eq!(IdLines::parse_measured_at(&lines[0]), Some(1_700_000_000_123_456));
        assert_eq!(IdLines::parse_estimated_error(&lines[4]), Some(-31.5));
        assert_eq!(IdLines::value(&lines[4], "seed"), Some("42"));
        assert_eq!(IdLines::value(&lines[4], "recipe"), Some("scan"));
        assert!(lines.iter().all(|l| l.len() <= 80));
    }

    #[test]
    fn the_measurement_time_survives_the_longest_quality_and_key() {
        // An SNR with 17 significant digits and the largest key: line 4 was cut at 80 columns, and the time with it.
        let meta = meta("scan", "metamaterial");
        let mut row = IrMeta::at_grid(&meta.grid, 0, 0, u16::MAX, 24_000.0).unwrap();
        row.point_index = u32::MAX;
        (row.status, row.snr_db, row.retries, row.measured_at_unix_us) =
            (Some(Status::Valid), Some(-61.234_567_890_123_45), Some(u32::MAX), Some(i64::MIN));
        let lines = SharedIds::new(&meta).for_row(&row);
        assert!(lines.iter().all(|l| l.len() <= 80), "{lines:?}");
        assert_eq!(IdLines::parse_measured_at(&lines[0]), Some(i64::MIN));
        assert_eq!(IdLines::parse_key(&lines[0]), Some((u32::MAX, u16::MAX)));
        assert_eq!(
            IdLines::parse_quality(&lines[3]),
            (Some(Status::Valid), Some(-61.234_567_890_123_45), Some(u32::MAX), None)
        );
        // A file of 0.6 with the time on line 4 still gives it.
        assert_eq!(IdLines::parse_quality("metaplate status=valid measured_at_us=17").3, Some(17));
    }

    #[test]
    fn a_row_without_quality_has_none_and_spaces_become_underscores_within_80_columns() {
        let long = "a scene with a name far too long for one line of eighty columns, and then some more";
        let meta = meta("simulate greens", long);
        let row = IrMeta::at_grid(&meta.grid, 0, 0, 0, 24_000.0).unwrap();
        let lines = SharedIds::new(&meta).for_row(&row);
        assert_eq!(lines[3], "metaplate");
        assert_eq!(IdLines::parse_quality(&lines[3]), (None, None, None, None));
        assert_eq!(IdLines::parse_estimated_error(&lines[4]), None);
        assert_eq!(IdLines::value(&lines[4], "recipe"), Some("simulate_greens"));
        assert_eq!(lines[2].len(), 80);
        assert!(IdLines::value(&lines[2], "scene").is_some_and(|s| s.starts_with("a_scene_with")));
    }

    #[test]
    fn lines_another_tool_wrote_are_not_read_as_metaplate_ones() {
        for line in ["NONE", "", "metaplatepoint=1 actuator=2", "Polytec PSV point=1 actuator=2"] {
            assert_eq!(IdLines::parse_key(line), None, "{line}");
            assert_eq!(IdLines::pairs(line), None, "{line}");
        }
        assert_eq!(IdLines::parse_grid("metaplate grid=0x3 spacing_m=0.005 origin_m=0,0"), None, "an invalid grid");
        assert_eq!(IdLines::parse_key("metaplate point=1 actuator=70000"), None, "an actuator beyond u16");
    }
}
