//! Faults injected into a replay, at cassette record indices.

use std::collections::BTreeMap;
use std::str::FromStr;

/// What happens to the recorded call at a record index. See the crate documentation for the replay semantics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FaultKind {
    /// The read returns a timeout; the recorded bytes arrive at the next read (a late reply).
    Timeout,
    /// The read returns a stall (a serial line has none: a timeout); the recorded bytes arrive at the next read.
    Stall,
    /// The recorded read is lost: the read gets what follows it.
    Drop,
    /// The read returns the recorded bytes with the middle byte's top bit flipped.
    Garble,
    /// The read returns the first half of the recorded bytes (rounded down, at least nothing); the rest is lost.
    Truncate,
    /// The link goes down at this call: it and every later call but a reopen report a disconnect.
    Disconnect,
}

impl FaultKind {
    /// Its name in a fault spec.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Timeout => "timeout",
            FaultKind::Stall => "stall",
            FaultKind::Drop => "drop",
            FaultKind::Garble => "garble",
            FaultKind::Truncate => "truncate",
            FaultKind::Disconnect => "disconnect",
        }
    }

    const ALL: [FaultKind; 6] = [
        FaultKind::Timeout,
        FaultKind::Stall,
        FaultKind::Drop,
        FaultKind::Garble,
        FaultKind::Truncate,
        FaultKind::Disconnect,
    ];
}

/// A fault spec that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FaultSpecError {
    /// Not `KIND@RECORD`.
    #[error("fault spec {spec:?} is not KIND@RECORD (kinds: timeout, stall, drop, garble, truncate, disconnect)")]
    Syntax {
        /// The spec given.
        spec: String,
    },
    /// Two faults at one record.
    #[error("two faults at record {record}")]
    Duplicate {
        /// The record index.
        record: usize,
    },
}

/// Faults to inject, at most one per cassette record index (the index of the record in the cassette, counted
/// from 0 over the good records, as `metaplate replay` lists them).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReplayFaults {
    at: BTreeMap<usize, FaultKind>,
}

impl ReplayFaults {
    /// No faults.
    pub fn none() -> Self {
        Self::default()
    }

    /// Adds `kind` at `record`.
    ///
    /// # Errors
    /// [`FaultSpecError::Duplicate`] if a fault is already there.
    pub fn add(&mut self, record: usize, kind: FaultKind) -> Result<(), FaultSpecError> {
        if self.at.insert(record, kind).is_some() {
            return Err(FaultSpecError::Duplicate { record });
        }
        Ok(())
    }

    /// `self` with `kind` at `record` added (replacing any fault there).
    pub fn with(mut self, record: usize, kind: FaultKind) -> Self {
        self.at.insert(record, kind);
        self
    }

    /// Parses specs such as `timeout@12`, `garble@30`.
    ///
    /// # Errors
    /// [`FaultSpecError`] for the first bad or duplicate spec.
    pub fn parse<S: AsRef<str>>(specs: &[S]) -> Result<Self, FaultSpecError> {
        let mut faults = Self::none();
        for spec in specs {
            let (kind, record) = parse_one(spec.as_ref())?;
            faults.add(record, kind)?;
        }
        Ok(faults)
    }

    /// `self` without the fault at `record`.
    pub fn without(mut self, record: usize) -> Self {
        self.at.remove(&record);
        self
    }

    /// The fault at `record`, if any.
    pub fn at(&self, record: usize) -> Option<FaultKind> {
        self.at.get(&record).copied()
    }

    /// Every fault, by record index.
    pub fn iter(&self) -> impl Iterator<Item = (usize, FaultKind)> + '_ {
        self.at.iter().map(|(r, k)| (*r, *k))
    }

    /// Number of faults.
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }
}

fn parse_one(spec: &str) -> Result<(FaultKind, usize), FaultSpecError> {
    let syntax = || FaultSpecError::Syntax { spec: spec.to_owned() };
    let (name, index) = spec.trim().split_once('@').ok_or_else(syntax)?;
    let kind = FaultKind::ALL.into_iter().find(|k| k.name() == name).ok_or_else(syntax)?;
    let record = index.parse().map_err(|_| syntax())?;
    Ok((kind, record))
}

impl FromStr for ReplayFaults {
    type Err = FaultSpecError;

    /// Comma-separated specs: `timeout@12,garble@30`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let specs: Vec<&str> = s.split(',').filter(|p| !p.trim().is_empty()).collect();
        Self::parse(&specs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_bad_ones_are_refused() {
        let faults: ReplayFaults = "timeout@12, garble@30,truncate@31,disconnect@40,stall@5,drop@0".parse().unwrap();
        assert_eq!(faults.len(), 6);
        assert_eq!(faults.at(12), Some(FaultKind::Timeout));
        assert_eq!(faults.at(0), Some(FaultKind::Drop));
        assert_eq!(faults.at(13), None);
        for bad in ["timeout", "timeout@", "@3", "melt@3", "timeout@-1", "timeout@1.5", "stall@99999999999999999999"] {
            assert!(matches!(ReplayFaults::parse(&[bad]), Err(FaultSpecError::Syntax { .. })), "{bad}");
        }
        assert_eq!(ReplayFaults::parse(&["drop@3", "stall@3"]), Err(FaultSpecError::Duplicate { record: 3 }));
    }
}
