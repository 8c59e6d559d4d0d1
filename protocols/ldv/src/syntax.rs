//! The words of a line: keywords shared by commands and replies, and a tokenizer over a line's content.
//!
//! Words are separated by one or more spaces; leading and trailing spaces are ignored; keywords match in any case.

use crate::error::LdvProtocolError;

/// Keywords, in their canonical (encoded) spelling. Queries are the keyword followed by `?`.
pub(crate) mod kw {
    pub const IDN_QUERY: &str = "*IDN?";
    pub const RESET: &str = "*RST";
    pub const CLEAR: &str = "*CLS";
    pub const POS: &str = "POS";
    pub const POS_QUERY: &str = "POS?";
    pub const ANG: &str = "ANG";
    pub const ANG_QUERY: &str = "ANG?";
    pub const SIG: &str = "SIG";
    pub const SIG_QUERY: &str = "SIG?";
    pub const VRANGE: &str = "VRANGE";
    pub const VRANGE_QUERY: &str = "VRANGE?";
    pub const TRACK: &str = "TRACK";
    pub const TRACK_QUERY: &str = "TRACK?";
    pub const LASER: &str = "LASER";
    pub const LASER_QUERY: &str = "LASER?";
    pub const CAL: &str = "CAL";
    pub const CAL_QUERY: &str = "CAL?";
    pub const SYNC: &str = "SYNC";
    pub const OK: &str = "OK";
    pub const ERR: &str = "ERR";
    pub const IDN: &str = "IDN";
}

/// The words of one line's content.
pub(crate) struct Tokens<'a> {
    rest: &'a str,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(line: &'a str) -> Self {
        Self { rest: line.trim_matches(' ') }
    }

    /// The next word, or `None` at the end of the line.
    pub(crate) fn next_word(&mut self) -> Option<&'a str> {
        if self.rest.is_empty() {
            return None;
        }
        let (word, rest) = self.rest.split_once(' ').unwrap_or((self.rest, ""));
        self.rest = rest.trim_start_matches(' ');
        Some(word)
    }

    /// Everything after the words taken so far, without leading or trailing spaces (free text).
    pub(crate) fn rest(&self) -> &'a str {
        self.rest
    }

    /// The remaining words, which must number exactly `N`: the arguments of `keyword`.
    ///
    /// # Errors
    /// [`LdvProtocolError::ArgumentCount`] otherwise.
    pub(crate) fn args<const N: usize>(mut self, keyword: &'static str) -> Result<[&'a str; N], LdvProtocolError> {
        let mut args = [""; N];
        let mut found = 0;
        while let Some(word) = self.next_word() {
            if let Some(slot) = args.get_mut(found) {
                *slot = word;
            }
            found += 1;
        }
        if found == N { Ok(args) } else { Err(LdvProtocolError::ArgumentCount { keyword, expected: N, found }) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_on_runs_of_spaces() {
        let mut t = Tokens::new("  POS   1.0 -2  ");
        assert_eq!(t.next_word(), Some("POS"));
        assert_eq!(t.rest(), "1.0 -2");
        assert_eq!(t.args::<2>("POS").unwrap(), ["1.0", "-2"]);
    }

    #[test]
    fn counts_arguments_exactly() {
        assert_eq!(Tokens::new("").args::<0>("X").unwrap(), [""; 0]);
        assert_eq!(
            Tokens::new("a b c").args::<2>("X"),
            Err(LdvProtocolError::ArgumentCount { keyword: "X", expected: 2, found: 3 })
        );
        assert_eq!(
            Tokens::new("a").args::<2>("X"),
            Err(LdvProtocolError::ArgumentCount { keyword: "X", expected: 2, found: 1 })
        );
    }

    #[test]
    fn rest_keeps_inner_spaces() {
        let mut t = Tokens::new("ERR 3  x  =  1 ");
        assert_eq!(t.next_word(), Some("ERR"));
        assert_eq!(t.next_word(), Some("3"));
        assert_eq!(t.rest(), "x  =  1");
        assert_eq!(t.next_word(), Some("x"));
    }
}
