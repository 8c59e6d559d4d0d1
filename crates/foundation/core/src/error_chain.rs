//! An error and its causes as one line of text, for a message a person reads.

use std::error::Error;

/// `error` and its causes (its `source()` chain) as one line, `outer: cause: deeper`. A cause whose text the line
/// already holds is left out: many errors print their source inside their own message (`"{op} {path}: {source}"`)
/// and also return it as their source, which a plain walk of the chain would print twice.
pub fn message(error: &(dyn Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !text.contains(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        source = cause.source();
    }
    text
}
