//! The rules that hold across a whole dataset, checked in one place for the writer and the reader alike: every row
//! valid against the grid, each (point, actuator) pair once, one impulse-response length and one sample rate.
//!
//! Checking is split from accepting so that a batch is taken whole or not at all: a writer whose commit fails leaves
//! its index as it was.

use std::collections::HashMap;

use crate::error::StoreError;
use crate::manifest::GridSpec;
use crate::record::{IrMeta, check_ir};

/// The (point, actuator) pairs seen so far, with the global row number of each, plus the dataset-wide IR length and
/// sample rate (set by the first row).
#[derive(Debug, Default)]
pub(crate) struct RowIndex {
    rows: HashMap<(u32, u16), usize>,
    /// First global row and label (a file name) of each accepted batch, in order.
    batches: Vec<(usize, String)>,
    len: usize,
    ir_len: Option<usize>,
    sample_rate_hz: Option<f64>,
}

/// A batch that passed [`RowIndex::check`], ready for [`RowIndex::accept`].
#[derive(Debug)]
pub(crate) struct Checked {
    label: String,
    keys: Vec<(u32, u16)>,
    ir_len: usize,
    sample_rate_hz: f64,
}

impl Checked {
    /// `(point_index, actuator)` of every row, in order.
    pub(crate) fn keys(&self) -> &[(u32, u16)] {
        &self.keys
    }

    /// The IR length of the batch, samples.
    pub(crate) fn ir_len(&self) -> usize {
        self.ir_len
    }

    /// The sample rate of the batch, Hz.
    pub(crate) fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }
}

impl RowIndex {
    /// Checks a batch labelled `label` (its file name) against `grid` and against every row accepted so far.
    ///
    /// # Errors
    /// [`StoreError::EmptyBatch`], [`StoreError::InvalidRecord`], [`StoreError::Inconsistent`] or
    /// [`StoreError::Duplicate`], naming the row.
    pub(crate) fn check<'a>(
        &self,
        label: &str,
        grid: &GridSpec,
        rows: impl IntoIterator<Item = (&'a IrMeta, &'a [f32])>,
    ) -> Result<Checked, StoreError> {
        let location = |row: usize| format!("{label} row {row}");
        let mut in_batch: HashMap<(u32, u16), usize> = HashMap::new();
        let mut keys = Vec::new();
        let (mut ir_len, mut sample_rate_hz) = (self.ir_len, self.sample_rate_hz);
        for (row, (meta, ir)) in rows.into_iter().enumerate() {
            let invalid = |reason| StoreError::InvalidRecord { location: location(row), reason };
            meta.check(grid).map_err(invalid)?;
            check_ir(ir).map_err(invalid)?;
            let expected_len = *ir_len.get_or_insert(ir.len());
            if ir.len() != expected_len {
                return Err(StoreError::Inconsistent {
                    location: location(row),
                    what: "ir length (samples)",
                    expected: expected_len.to_string(),
                    found: ir.len().to_string(),
                });
            }
            let expected_rate = *sample_rate_hz.get_or_insert(meta.sample_rate_hz);
            if meta.sample_rate_hz != expected_rate {
                return Err(StoreError::Inconsistent {
                    location: location(row),
                    what: "sample_rate_hz",
                    expected: expected_rate.to_string(),
                    found: meta.sample_rate_hz.to_string(),
                });
            }
            let key = meta.key();
            self.refuse_duplicate(key, row, &in_batch, &location)?;
            in_batch.insert(key, row);
            keys.push(key);
        }
        match (ir_len, sample_rate_hz) {
            (Some(ir_len), Some(sample_rate_hz)) if !keys.is_empty() => {
                Ok(Checked { label: label.to_string(), keys, ir_len, sample_rate_hz })
            }
            _ => Err(StoreError::EmptyBatch),
        }
    }

    /// Refuses `key` at `row` of a batch (described by `location`) when an accepted batch or an earlier row of this
    /// one (`in_batch`: key to row) already holds it, naming the first holder.
    fn refuse_duplicate(
        &self,
        key: (u32, u16),
        row: usize,
        in_batch: &HashMap<(u32, u16), usize>,
        location: &dyn Fn(usize) -> String,
    ) -> Result<(), StoreError> {
        let first = match (self.rows.get(&key), in_batch.get(&key)) {
            (Some(&global), _) => self.describe(global),
            (None, Some(&earlier)) => location(earlier),
            (None, None) => return Ok(()),
        };
        Err(StoreError::Duplicate { point_index: key.0, actuator: key.1, first, location: location(row) })
    }

    /// Takes a checked batch into the index; its rows get the next global row numbers, in order.
    pub(crate) fn accept(&mut self, checked: Checked) {
        self.batches.push((self.len, checked.label));
        for key in checked.keys {
            self.rows.insert(key, self.len);
            self.len += 1;
        }
        self.ir_len = Some(checked.ir_len);
        self.sample_rate_hz = Some(checked.sample_rate_hz);
    }

    /// Takes a batch known only by its journal entry (keys, IR length, sample rate), without reading its rows.
    ///
    /// # Errors
    /// [`StoreError::Duplicate`] or [`StoreError::Inconsistent`] against the rows accepted so far; nothing is taken.
    pub(crate) fn restore(
        &mut self,
        label: &str,
        keys: &[(u32, u16)],
        ir_len: usize,
        sample_rate_hz: f64,
    ) -> Result<(), StoreError> {
        let location = |row: usize| format!("{label} row {row}");
        for (what, expected, found) in [
            ("ir length (samples)", self.ir_len.map(|v| v.to_string()), ir_len.to_string()),
            ("sample_rate_hz", self.sample_rate_hz.map(|v| v.to_string()), sample_rate_hz.to_string()),
        ] {
            if let Some(expected) = expected.filter(|e| *e != found) {
                return Err(StoreError::Inconsistent { location: location(0), what, expected, found });
            }
        }
        let mut in_batch = HashMap::new();
        for (row, key) in keys.iter().enumerate() {
            self.refuse_duplicate(*key, row, &in_batch, &location)?;
            in_batch.insert(*key, row);
        }
        if keys.is_empty() {
            return Err(StoreError::EmptyBatch);
        }
        self.accept(Checked { label: label.to_string(), keys: keys.to_vec(), ir_len, sample_rate_hz });
        Ok(())
    }

    /// Every `(point_index, actuator)` accepted, in no particular order.
    pub(crate) fn keys(&self) -> impl Iterator<Item = (u32, u16)> + '_ {
        self.rows.keys().copied()
    }

    /// Whether `(point_index, actuator)` was accepted.
    pub(crate) fn contains(&self, key: (u32, u16)) -> bool {
        self.rows.contains_key(&key)
    }

    /// Global row number of `(point_index, actuator)`.
    pub(crate) fn row(&self, point_index: u32, actuator: u16) -> Option<usize> {
        self.rows.get(&(point_index, actuator)).copied()
    }

    /// Number of rows accepted.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The dataset's IR length, samples (`None` before the first batch).
    pub(crate) fn ir_len(&self) -> Option<usize> {
        self.ir_len
    }

    /// The dataset's sample rate, Hz (`None` before the first batch).
    pub(crate) fn sample_rate_hz(&self) -> Option<f64> {
        self.sample_rate_hz
    }

    /// `"<file> row <n>"` for a global row number.
    fn describe(&self, global: usize) -> String {
        let batch = self.batches.partition_point(|(start, _)| *start <= global).saturating_sub(1);
        match self.batches.get(batch) {
            Some((start, label)) => format!("{label} row {}", global - start),
            None => format!("row {global}"),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    const GRID: GridSpec = GridSpec { nx: 3, ny: 2, spacing_m: 0.01, origin_x_m: 0.0, origin_y_m: 0.0 };

    fn meta(ix: u32, iy: u32, actuator: u16) -> IrMeta {
        IrMeta::at_grid(&GRID, ix, iy, actuator, 24_000.0).unwrap()
    }

    #[test]
    fn accepts_distinct_rows_and_numbers_them_in_order() {
        let mut index = RowIndex::default();
        let (a, b, c) = (meta(0, 0, 0), meta(2, 1, 0), meta(0, 0, 1));
        let ir = [1.0f32, 2.0];
        let checked = index.check("b0", &GRID, [(&a, &ir[..]), (&b, &ir[..])]).unwrap();
        index.accept(checked);
        let checked = index.check("b1", &GRID, [(&c, &ir[..])]).unwrap();
        index.accept(checked);
        assert_eq!(index.len(), 3);
        assert_eq!(index.row(5, 0), Some(1));
        assert_eq!(index.row(0, 1), Some(2));
        assert_eq!(index.row(1, 0), None);
        assert_eq!((index.ir_len(), index.sample_rate_hz()), (Some(2), Some(24_000.0)));
    }

    #[test]
    fn duplicates_are_named_with_both_locations_and_leave_the_index_unchanged() {
        let mut index = RowIndex::default();
        let (a, b) = (meta(1, 0, 3), meta(2, 0, 3));
        let ir = [0.5f32];
        let checked = index.check("b0", &GRID, [(&a, &ir[..])]).unwrap();
        index.accept(checked);
        // Against an earlier batch.
        let err = index.check("b1", &GRID, [(&b, &ir[..]), (&a, &ir[..])]).unwrap_err();
        match err {
            StoreError::Duplicate { point_index: 1, actuator: 3, first, location } => {
                assert_eq!((first.as_str(), location.as_str()), ("b0 row 0", "b1 row 1"));
            }
            other => panic!("unexpected {other}"),
        }
        // Within one batch.
        let err = index.check("b1", &GRID, [(&b, &ir[..]), (&b, &ir[..])]).unwrap_err();
        assert!(matches!(err, StoreError::Duplicate { ref first, .. } if first == "b1 row 0"), "{err}");
        // The failed checks accepted nothing: b is still free.
        assert_eq!(index.len(), 1);
        assert!(index.check("b1", &GRID, [(&b, &ir[..])]).is_ok());
    }

    #[test]
    fn mixed_lengths_and_rates_are_refused_within_and_across_batches() {
        let mut index = RowIndex::default();
        let (a, b) = (meta(0, 0, 0), meta(1, 0, 0));
        let err = index.check("b0", &GRID, [(&a, &[1.0f32, 2.0][..]), (&b, &[1.0f32][..])]).unwrap_err();
        assert!(matches!(err, StoreError::Inconsistent { what: "ir length (samples)", .. }), "{err}");
        let checked = index.check("b0", &GRID, [(&a, &[1.0f32][..])]).unwrap();
        index.accept(checked);
        let other_rate = IrMeta { sample_rate_hz: 48_000.0, ..b };
        let err = index.check("b1", &GRID, [(&other_rate, &[1.0f32][..])]).unwrap_err();
        assert!(matches!(err, StoreError::Inconsistent { what: "sample_rate_hz", .. }), "{err}");
    }

    #[test]
    fn empty_and_invalid_batches_are_refused() {
        let index = RowIndex::default();
        assert!(matches!(index.check("b0", &GRID, []), Err(StoreError::EmptyBatch)));
        let a = meta(0, 0, 0);
        let err = index.check("b0", &GRID, [(&a, &[f32::NAN][..])]).unwrap_err();
        assert!(matches!(err, StoreError::InvalidRecord { ref location, .. } if location == "b0 row 0"), "{err}");
        let off_grid = IrMeta { ix: 3, point_index: 3, ..a };
        assert!(matches!(
            index.check("b0", &GRID, [(&off_grid, &[0.0f32][..])]),
            Err(StoreError::InvalidRecord { .. })
        ));
    }
}
