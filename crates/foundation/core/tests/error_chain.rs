//! `error_chain::message`: each cause once, in order.

use std::fmt;

use metaplate_core::error_chain::message;

/// An error with a message and an optional source; `echo` prints the source inside its own message as well.
#[derive(Debug)]
struct Layer {
    text: &'static str,
    echo: bool,
    source: Option<Box<Layer>>,
}

impl fmt::Display for Layer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.source, self.echo) {
            (Some(source), true) => write!(f, "{}: {source}", self.text),
            _ => f.write_str(self.text),
        }
    }
}

impl std::error::Error for Layer {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.source.as_deref().map(|s| s as _)
    }
}

fn layer(text: &'static str, echo: bool, source: Option<Layer>) -> Layer {
    Layer { text, echo, source: source.map(Box::new) }
}

#[test]
fn causes_follow_after_colons_each_once() {
    let os = layer("Is a directory (os error 21)", false, None);
    // A store-style error that prints its source and returns it, under a context that does not.
    let store = layer("rename into place /tmp/rep", true, Some(os));
    let context = layer("cannot write the report /tmp/rep", false, Some(store));
    assert_eq!(
        message(&context),
        "cannot write the report /tmp/rep: rename into place /tmp/rep: Is a directory (os error 21)"
    );
    // Without echoes every cause is appended; a lone error is its own text.
    let plain = layer("outer", false, Some(layer("middle", false, Some(layer("inner", false, None)))));
    assert_eq!(message(&plain), "outer: middle: inner");
    assert_eq!(message(&layer("alone", false, None)), "alone");
    // Only the parent is compared: a cause an unrelated outer layer happens to contain is kept.
    let unrelated =
        layer("reading /data/timed out/x.json", false, Some(layer("io", false, Some(layer("timed out", false, None)))));
    assert_eq!(message(&unrelated), "reading /data/timed out/x.json: io: timed out");
}
