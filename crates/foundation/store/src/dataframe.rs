//! A polars `DataFrame` of the committed batch files (cargo feature `polars`).

use std::fs::File;
use std::path::Path;

use polars_core::frame::DataFrame;
use polars_io::SerReader;
use polars_io::parquet::read::ParquetReader;

use crate::error::StoreError;
use crate::reader::Dataset;

impl Dataset {
    /// A polars `DataFrame` of every row of the committed files ([`Dataset::committed_files`]), in the columns of
    /// [`crate::schema`], in commit order. `columns`: only these, in this order (`None`: all); naming only the
    /// small columns (`point_index`, `actuator`, `snr_db`) skips reading the impulse responses. Nothing is verified
    /// here (polars reads the files itself): use [`Dataset::open`] to verify.
    ///
    /// The frame is `polars_core`'s, the one the `polars` crate re-exports: a program with polars' `lazy`
    /// feature turns it into a `LazyFrame` with `.lazy()`. It is read whole into memory: about 4 bytes per
    /// impulse-response sample (1,225 points x 8 actuators x 12,000 samples is 470 MB).
    ///
    /// # Errors
    /// The manifest errors of [`Dataset::open`]; [`StoreError::EmptyDataset`] if nothing is committed;
    /// [`StoreError::Io`] if a committed file cannot be opened; [`StoreError::Polars`] if polars refuses a file
    /// or a column name, or the files' columns differ.
    pub fn dataframe(dir: impl AsRef<Path>, columns: Option<&[&str]>) -> Result<DataFrame, StoreError> {
        let dir = dir.as_ref();
        let polars = |reason: String| StoreError::Polars { dir: dir.to_path_buf(), reason };
        let columns: Option<Vec<String>> = columns.map(|names| names.iter().map(|name| (*name).to_owned()).collect());
        let mut frame: Option<DataFrame> = None;
        for path in Self::committed_files(dir)? {
            let file = File::open(&path).map_err(|source| StoreError::from_io("open", path.clone(), source))?;
            let batch = ParquetReader::new(file)
                .with_columns(columns.clone())
                .finish()
                .map_err(|e| polars(format!("{}: {e}", path.display())))?;
            frame = Some(match frame {
                None => batch,
                Some(mut all) => {
                    all.vstack_mut_owned(batch).map_err(|e| polars(format!("{}: {e}", path.display())))?;
                    all
                }
            });
        }
        // `committed_files` refuses an empty dataset, so one file at least was read. One chunk per column, not one
        // per committed file (hundreds for a full scan), as polars' own readers give.
        let mut frame = frame.ok_or_else(|| StoreError::EmptyDataset { dir: dir.to_path_buf() })?;
        frame.rechunk_mut();
        Ok(frame)
    }
}
