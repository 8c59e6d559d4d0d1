//! What a long evaluation tells its caller while it runs: the steps it takes (a spinner's label), and the recipes'
//! events (a progress bar) through [`metaplate_recipes::Observer`].

use metaplate_recipes::{Event, Observer};

/// Told of an evaluation's steps and of the recipes' events.
pub trait Progress: Observer {
    /// A step starts: `label` says what (for a calibration or scan, the recipe's events follow until [`end`]).
    ///
    /// [`end`]: Progress::end
    fn begin(&mut self, label: &str);
    /// The step ends.
    fn end(&mut self);
}

/// Tells nobody.
#[derive(Debug, Default, Clone, Copy)]
pub struct Quiet;

impl Observer for Quiet {
    fn event(&mut self, _event: &Event) {}
}

impl Progress for Quiet {
    fn begin(&mut self, _label: &str) {}
    fn end(&mut self) {}
}
