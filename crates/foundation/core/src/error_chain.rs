//! An error and its causes as one line of text, for a message a person reads.

use std::error::Error;

/// `error` and its causes (its `source()` chain) as one line, `outer: cause: deeper`. A cause whose text its
/// parent's own message already holds is left out: many errors print their source inside their message (`"{op}
/// {path}: {source}"`) and also return it as their source, which a plain walk of the chain would print twice. Only
/// the parent is compared, so a short cause (`"timed out"`) is kept when some other layer happens to contain it.
pub fn message(error: &(dyn Error + 'static)) -> String {
    let mut parent_text = error.to_string();
    let mut text = parent_text.clone();
    let mut source = error.source();
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !parent_text.contains(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        parent_text = cause_text;
        source = cause.source();
    }
    text
}
