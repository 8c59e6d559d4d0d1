//! `manifest.json`: what a dataset is (recipe, configuration, scene, grid, seed), which batch files it holds, and
//! hashes that tie it together.
//!
//! The JSON object is flat: the fields of [`DatasetMeta`] followed by `created_at`, `batches` and `config_hash`.

use std::collections::HashSet;
use std::fs;
use std::io::Write;
use std::path::Path;

pub use metaplate_core::grid::GridSpec;
pub use metaplate_core::scene::SceneId;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::checksum;
use crate::durable::{self, TEMP_SUFFIX, WriteBudget};
use crate::error::StoreError;

/// The schema version this build writes and reads. Bump it whenever a column or a manifest field changes meaning.
pub const SCHEMA_VERSION: u32 = 1;

/// File name of the manifest inside a dataset directory.
pub const MANIFEST_FILE: &str = "manifest.json";

/// Subdirectory of a dataset directory that holds the batch files and nothing else, so that
/// `pyarrow.parquet.read_table(f"{run}/batches")`, `pandas.read_parquet(...)` and `polars.read_parquet(...)` read the
/// whole dataset in one call (they refuse a directory that also holds `manifest.json`).
pub const BATCH_DIR: &str = "batches";

/// What a dataset is: everything in the manifest that identifies the run, and that `config_hash` covers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetMeta {
    /// Schema version of the batch files and manifest ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// The recipe that produced the dataset, for example `"simulate-greens"` or `"scan"`.
    pub recipe: String,
    /// The recipe's fully resolved configuration (a JSON object).
    pub config: Map<String, Value>,
    /// The plate.
    pub scene: SceneId,
    /// Version of the software that wrote the dataset (for example `env!("CARGO_PKG_VERSION")` of the binary).
    pub software_version: String,
    /// Seed of every random generator of the run.
    pub seed: u64,
    /// The measurement grid.
    pub grid: GridSpec,
    /// What the `ir` column holds (its unit, the samples before time 0), written into every batch file's key-value
    /// metadata too; `None` for datasets written before it existed (absent from their manifest, so their
    /// `config_hash` is unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<DatasetDescription>,
    /// Where the points are when they lie on no lattice (a scan mesh imported from another tool); `grid` is then an
    /// index of them (`nx` points, `ny` 1) that says nothing of their positions. `None` for a dataset on its grid
    /// (absent from its manifest, so its `config_hash` is unchanged).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scattered: Option<ScatteredPoints>,
}

/// Points on no lattice: each point's position in the plane of the points, by point index.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScatteredPoints {
    /// Position (x, y) of point `i` (the grid's flat index), m, in the frame `frame` says.
    pub positions_m: Vec<(f64, f64)>,
    /// The frame of the positions, in words (for example the plane fitted to 3-D nodes, and its axes).
    pub frame: String,
}

/// [`DatasetDescription::ir_unit`] of plate velocity per actuator force: the simulated ground truth, and imports.
pub const IR_UNIT_M_S_PER_N: &str = "m/s/N";

/// What the `ir` column of a dataset holds, stated so that a batch file read alone says it
/// ([`crate::schema::file_metadata`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DatasetDescription {
    /// Unit of the `ir` samples, as text: `"m/s/N"` (plate velocity per actuator force: ground truth, imports),
    /// `"m/s per full-scale drive"` (a scan), or a sentence where it depends on the row (a calibration).
    pub ir_unit: String,
    /// Samples of every `ir` before time 0 (time 0 at index `pre_samples`; 0: causal).
    pub pre_samples: u32,
}

impl DatasetMeta {
    /// Metadata at the current [`SCHEMA_VERSION`].
    pub fn new(
        recipe: impl Into<String>,
        config: Map<String, Value>,
        scene: SceneId,
        software_version: impl Into<String>,
        seed: u64,
        grid: GridSpec,
    ) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            recipe: recipe.into(),
            config,
            scene,
            software_version: software_version.into(),
            seed,
            grid,
            description: None,
            scattered: None,
        }
    }

    /// This metadata of scattered points ([`DatasetMeta::scattered`]): the grid becomes their index,
    /// `positions_m.len()` x 1, with `spacing_m` kept (a typical distance between the points, m).
    #[must_use]
    pub fn with_scattered(mut self, scattered: ScatteredPoints) -> Self {
        let (origin_x_m, origin_y_m) = scattered.positions_m.first().copied().unwrap_or_default();
        self.grid =
            GridSpec { nx: scattered.positions_m.len(), ny: 1, spacing_m: self.grid.spacing_m, origin_x_m, origin_y_m };
        self.scattered = Some(scattered);
        self
    }

    /// Position of point `point_index`, m: its scattered position ([`DatasetMeta::scattered`]), else its node of
    /// the grid; `None` beyond the points.
    pub fn position_m(&self, point_index: usize) -> Option<(f64, f64)> {
        match &self.scattered {
            Some(s) => s.positions_m.get(point_index).copied(),
            None => (point_index < self.grid.len()).then(|| self.grid.position_m(point_index)),
        }
    }

    /// This metadata with `description` ([`DatasetMeta::description`]).
    #[must_use]
    pub fn with_description(mut self, description: DatasetDescription) -> Self {
        self.description = Some(description);
        self
    }

    /// Checks that the metadata can be written: current schema version, non-empty recipe, valid grid.
    ///
    /// # Errors
    /// [`StoreError::UnsupportedSchemaVersion`] or [`StoreError::InvalidMeta`].
    pub fn validate(&self) -> Result<(), StoreError> {
        if self.schema_version != SCHEMA_VERSION {
            return Err(StoreError::UnsupportedSchemaVersion { found: self.schema_version, supported: SCHEMA_VERSION });
        }
        if self.recipe.trim().is_empty() {
            return Err(StoreError::InvalidMeta { field: "recipe", reason: "must not be empty".into() });
        }
        self.grid.validate().map_err(|e| StoreError::InvalidMeta { field: "grid", reason: e.to_string() })?;
        if let Some(s) = &self.scattered {
            let invalid = |reason: String| Err(StoreError::InvalidMeta { field: "scattered", reason });
            if s.positions_m.len() != self.grid.len() || self.grid.ny != 1 {
                return invalid(format!(
                    "{} positions for a {} x {} grid; scattered points are indexed by a grid of one row, one node each",
                    s.positions_m.len(),
                    self.grid.nx,
                    self.grid.ny
                ));
            }
            if let Some(i) = s.positions_m.iter().position(|p| !(p.0.is_finite() && p.1.is_finite())) {
                return invalid(format!("point {i}'s position is not finite"));
            }
        }
        Ok(())
    }

    /// SHA-256 of the canonical JSON of this metadata (see [`canonical_json`]), as `"sha256:<hex>"`: equal metadata
    /// give equal hashes on every machine, whatever the key order of `config`.
    pub fn config_hash(&self) -> String {
        // Serialising plain data with string keys cannot fail; were it ever to, hashing the empty object still
        // yields a hash that no real metadata matches, so a mismatch is reported on open rather than a panic here.
        let value = serde_json::to_value(self).unwrap_or(Value::Object(Map::new()));
        checksum::sha256(canonical_json(&value).as_bytes())
    }
}

/// JSON with object keys sorted (by UTF-8 bytes, recursively) and no whitespace; strings and numbers as `serde_json`
/// writes them (shortest round-trip floats). The same value always gives the same text, independent of insertion
/// order and of serde_json's `preserve_order` feature.
pub fn canonical_json(value: &Value) -> String {
    let mut out = String::new();
    write_canonical(value, &mut out);
    out
}

fn write_canonical(value: &Value, out: &mut String) {
    match value {
        Value::Object(map) => {
            let mut entries: Vec<_> = map.iter().collect();
            entries.sort_unstable_by(|a, b| a.0.cmp(b.0));
            out.push('{');
            for (i, (key, item)) in entries.into_iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                out.push_str(&Value::String(key.clone()).to_string());
                out.push(':');
                write_canonical(item, out);
            }
            out.push('}');
        }
        Value::Array(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                write_canonical(item, out);
            }
            out.push(']');
        }
        scalar => out.push_str(&scalar.to_string()),
    }
}

/// One committed batch file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct BatchInfo {
    /// File name inside the dataset's [`BATCH_DIR`] (no directory part).
    pub file: String,
    /// Number of rows (one per point and actuator).
    pub rows: u64,
    /// File size, bytes; tells a truncated file from a corrupt one.
    pub size_bytes: u64,
    /// SHA-256 of the file's bytes, `"sha256:<hex>"` (check with `sha256sum`).
    pub checksum: String,
}

/// The content of `manifest.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// What the dataset is.
    #[serde(flatten)]
    pub meta: DatasetMeta,
    /// When the writer was created, ISO-8601 UTC (`2026-01-31T23:59:59.999Z`).
    pub created_at: String,
    /// Committed batch files, in commit order.
    pub batches: Vec<BatchInfo>,
    /// [`DatasetMeta::config_hash`] of `meta`.
    pub config_hash: String,
}

impl Manifest {
    /// Reads and checks `dir/manifest.json`: the JSON parses, the schema version is supported, the metadata is in
    /// range, `config_hash` matches the content, and every batch entry names a plain file name (resolved in
    /// [`BATCH_DIR`]) with a well-formed checksum, each file once.
    ///
    /// # Errors
    /// [`StoreError::ManifestMissing`], [`StoreError::ManifestMalformed`], [`StoreError::UnsupportedSchemaVersion`],
    /// [`StoreError::ConfigHashMismatch`], or [`StoreError::Io`].
    pub fn read(dir: &Path) -> Result<Self, StoreError> {
        let path = dir.join(MANIFEST_FILE);
        let text = match fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(StoreError::ManifestMissing { path }),
            Err(e) => return Err(StoreError::Io { op: "read", path, source: e }),
        };
        let malformed = |reason: String| StoreError::ManifestMalformed { path: path.clone(), reason };
        // Look at the version before the full structure, so that a newer manifest is reported as newer, not as
        // malformed.
        let value: Value = serde_json::from_str(&text).map_err(|e| malformed(e.to_string()))?;
        if let Some(found) = value.get("schema_version").and_then(Value::as_u64)
            && found != u64::from(SCHEMA_VERSION)
        {
            let found = u32::try_from(found).unwrap_or(u32::MAX);
            return Err(StoreError::UnsupportedSchemaVersion { found, supported: SCHEMA_VERSION });
        }
        let manifest: Manifest = serde_json::from_value(value).map_err(|e| malformed(e.to_string()))?;
        manifest.meta.validate().map_err(|e| malformed(e.to_string()))?;
        let computed = manifest.meta.config_hash();
        if computed != manifest.config_hash {
            return Err(StoreError::ConfigHashMismatch { stored: manifest.config_hash, computed });
        }
        let mut seen = HashSet::new();
        for batch in &manifest.batches {
            if !is_batch_file_name(&batch.file) {
                return Err(malformed(format!(
                    "batch file name {:?} is not a plain visible *.parquet name inside the dataset directory",
                    batch.file
                )));
            }
            if !seen.insert(batch.file.as_str()) {
                return Err(malformed(format!("batch file {} is listed twice", batch.file)));
            }
            if !checksum::is_well_formed(&batch.checksum) {
                return Err(malformed(format!(
                    "batch file {}: checksum {:?} is not sha256:<hex>",
                    batch.file, batch.checksum
                )));
            }
        }
        Ok(manifest)
    }

    /// Writes `dir/manifest.json` durably (temporary file, fsync, atomic rename, directory fsync), pretty-printed.
    ///
    /// # Errors
    /// [`StoreError::Io`].
    pub fn write(&self, dir: &Path) -> Result<(), StoreError> {
        self.write_with(dir, &WriteBudget::default())
    }

    /// As [`Manifest::write`], drawing on a writer's budget.
    pub(crate) fn write_with(&self, dir: &Path, budget: &WriteBudget) -> Result<(), StoreError> {
        let path = dir.join(MANIFEST_FILE);
        let text = serde_json::to_vec_pretty(self)
            .map_err(|e| StoreError::ManifestMalformed { path: path.clone(), reason: e.to_string() })?;
        durable::write_file(dir, MANIFEST_FILE, budget, |sink| {
            sink.write_all(&text).and_then(|()| sink.write_all(b"\n")).map_err(StoreError::io("write", &path))
        })?;
        Ok(())
    }
}

/// Whether `name` may be a batch file: a plain, visible `*.parquet` file name (no directory part, so a manifest
/// cannot point outside its dataset directory).
pub(crate) fn is_batch_file_name(name: &str) -> bool {
    name.ends_with(".parquet")
        && name.len() > ".parquet".len()
        && !name.starts_with('.')
        && !name.ends_with(TEMP_SUFFIX)
        && !name.contains(['/', '\\', '\0'])
        && Path::new(name).file_name().is_some_and(|f| f == name)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    pub(crate) fn sample_meta() -> DatasetMeta {
        let config = serde_json::json!({"band_hz": [62.0, 625.0], "ir_len": 12000, "plate": {"h_m": 0.0015}});
        DatasetMeta::new(
            "simulate-greens",
            config.as_object().cloned().unwrap(),
            SceneId { name: "acrylic".into(), hash: "sha256:00".into() },
            "0.1.0",
            42,
            GridSpec::centred(49, 25, 0.005),
        )
    }

    #[test]
    fn scattered_points_are_indexed_by_a_one_row_grid_and_absent_from_a_grid_datasets_manifest() {
        let meta = sample_meta();
        let json = serde_json::to_value(&meta).unwrap();
        assert!(json.get("scattered").is_none(), "a dataset on its grid keeps its manifest and config_hash");
        let positions_m = vec![(0.01, 0.02), (-0.03, 0.5), (0.2, -0.1)];
        let frame = "the plane z = const".to_owned();
        let scattered = meta.clone().with_scattered(ScatteredPoints { positions_m, frame });
        scattered.validate().unwrap();
        assert_eq!((scattered.grid.nx, scattered.grid.ny), (3, 1));
        assert_eq!((scattered.position_m(1), scattered.position_m(3)), (Some((-0.03, 0.5)), None));
        assert_eq!(meta.position_m(0), Some(meta.grid.position_m(0)));
        assert_ne!(scattered.config_hash(), meta.config_hash());
        let mut wrong = scattered.clone();
        wrong.grid.nx = 4;
        assert!(matches!(wrong.validate(), Err(StoreError::InvalidMeta { field: "scattered", .. })));
        let mut nan = scattered;
        if let Some(s) = nan.scattered.as_mut() {
            s.positions_m[2].0 = f64::NAN;
        }
        assert!(matches!(nan.validate(), Err(StoreError::InvalidMeta { field: "scattered", .. })));
    }

    #[test]
    fn canonical_json_sorts_keys_recursively_and_has_no_whitespace() {
        let a: Value = serde_json::from_str(r#"{"b": 1, "a": {"y": [1, {"d": 2, "c": 3}], "x": null}}"#).unwrap();
        assert_eq!(canonical_json(&a), r#"{"a":{"x":null,"y":[1,{"c":3,"d":2}]},"b":1}"#);
    }

    #[test]
    fn config_hash_ignores_key_order_and_sees_every_field() {
        let meta = sample_meta();
        let mut reordered = meta.clone();
        reordered.config =
            serde_json::from_str(r#"{"plate": {"h_m": 0.0015}, "ir_len": 12000, "band_hz": [62.0, 625.0]}"#).unwrap();
        assert_eq!(meta.config_hash(), reordered.config_hash());
        assert!(checksum::is_well_formed(&meta.config_hash()));

        let mut changed = meta.clone();
        changed.seed += 1;
        assert_ne!(meta.config_hash(), changed.config_hash());
        let mut changed = meta.clone();
        changed.grid.spacing_m = 0.0051;
        assert_ne!(meta.config_hash(), changed.config_hash());
        let mut changed = meta.clone();
        changed.config.insert("ir_len".into(), 12001.into());
        assert_ne!(meta.config_hash(), changed.config_hash());
    }

    #[test]
    fn batch_file_names() {
        assert!(is_batch_file_name("batch-000000.parquet"));
        for bad in ["", ".parquet", "../x.parquet", "a/b.parquet", ".hidden.parquet", "x.json", "a\\b.parquet", ".."] {
            assert!(!is_batch_file_name(bad), "{bad:?}");
        }
    }

    #[test]
    fn validate_refuses_other_schema_versions_and_empty_recipes() {
        let mut meta = sample_meta();
        meta.schema_version = SCHEMA_VERSION + 1;
        assert!(matches!(meta.validate(), Err(StoreError::UnsupportedSchemaVersion { .. })));
        let mut meta = sample_meta();
        meta.recipe = "  ".into();
        assert!(matches!(meta.validate(), Err(StoreError::InvalidMeta { field: "recipe", .. })));
        // The grid's own rules (metaplate_core) apply: an empty grid or a NaN spacing is refused.
        let mut meta = sample_meta();
        meta.grid.nx = 0;
        assert!(matches!(meta.validate(), Err(StoreError::InvalidMeta { field: "grid", .. })));
        let mut meta = sample_meta();
        meta.grid.spacing_m = f64::NAN;
        assert!(matches!(meta.validate(), Err(StoreError::InvalidMeta { field: "grid", .. })));
    }
}
