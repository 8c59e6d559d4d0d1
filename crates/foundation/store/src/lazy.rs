//! A polars `LazyFrame` over the committed batch files (cargo feature `polars`).

use std::path::Path;

use polars::prelude::{LazyFrame, PlRefPath, ScanArgsParquet};

use crate::error::StoreError;
use crate::reader::Dataset;

impl Dataset {
    /// A polars `LazyFrame` scanning the committed files ([`Dataset::committed_files`]), in the columns of
    /// [`crate::schema`]. Nothing is verified here (polars reads the files itself): use [`Dataset::open`] to verify.
    ///
    /// # Errors
    /// The manifest errors of [`Dataset::open`]; [`StoreError::EmptyDataset`] if nothing is committed;
    /// [`StoreError::Polars`] if polars refuses the scan (for example a path that is not UTF-8).
    pub fn lazy(dir: impl AsRef<Path>) -> Result<LazyFrame, StoreError> {
        let dir = dir.as_ref();
        let polars = |reason: String| StoreError::Polars { dir: dir.to_path_buf(), reason };
        let paths = Self::committed_files(dir)?
            .into_iter()
            .map(|path| {
                path.to_str().map(PlRefPath::new).ok_or_else(|| polars(format!("{} is not UTF-8", path.display())))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let args = ScanArgsParquet { glob: false, ..ScanArgsParquet::default() };
        LazyFrame::scan_parquet_files(paths.into_iter().collect(), args).map_err(|e| polars(e.to_string()))
    }
}
