//! The built-in experiments as `metaplate experiment list` prints them (JSON keys in alphabetical order).

use serde::Serialize;

use crate::builtin;
use crate::error::ExperimentError;

/// One built-in experiment as `experiment list --json` prints it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExperimentListing {
    /// Accuracy by guessing.
    pub chance: f64,
    /// Conditions (stimuli).
    pub conditions: usize,
    /// One line for people.
    pub description: String,
    /// Unscored familiarisation trials.
    pub familiarisation_trials: usize,
    /// The file's hash.
    pub file_hash: String,
    /// The name.
    pub name: String,
    /// The pixels.
    pub pixels: Vec<ListedPixel>,
    /// Scored repeats of every condition.
    pub repeats: u32,
    /// The response labels.
    pub responses: Vec<String>,
    /// Scored trials.
    pub scored_trials: usize,
}

/// A pixel of an [`ExperimentListing`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ListedPixel {
    /// Its name.
    pub name: String,
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
}

/// The built-in experiments.
///
/// # Errors
/// A built-in that does not parse (a bug).
pub fn list_builtins() -> Result<Vec<ExperimentListing>, ExperimentError> {
    builtin::names()
        .into_iter()
        .map(|name| {
            let e = builtin::builtin(name)?;
            Ok(ExperimentListing {
                chance: e.chance,
                conditions: e.stimuli.len(),
                description: e.description.clone(),
                familiarisation_trials: if e.phases.familiarisation { e.stimuli.len() } else { 0 },
                file_hash: e.file_hash(),
                name: name.to_owned(),
                pixels: e.pixels.iter().map(|p| ListedPixel { name: p.name.clone(), x_m: p.x_m, y_m: p.y_m }).collect(),
                repeats: e.phases.repeats,
                responses: e.labels().iter().map(|l| (*l).to_owned()).collect(),
                scored_trials: e.stimuli.len() * e.phases.repeats as usize,
            })
        })
        .collect()
}

impl std::fmt::Display for ExperimentListing {
    /// The line `experiment list` prints.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<25} {:>2} conditions x {:>2} + {:>2} familiarisation = {:>3} trials, chance {:>2.0} %  {}",
            self.name,
            self.conditions,
            self.repeats,
            self.familiarisation_trials,
            self.scored_trials + self.familiarisation_trials,
            self.chance * 100.0,
            self.description
        )
    }
}
