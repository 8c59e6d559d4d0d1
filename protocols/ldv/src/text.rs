//! Validated free-text fields of replies: identity fields and error texts.
//!
//! Both are printable ASCII with no leading or trailing space, short enough that every reply fits in one line; so
//! a reply built from them always encodes, and decodes back to itself.

use std::fmt;

use crate::error::LdvProtocolError;

/// The longest identity field (vendor, model, serial number, firmware), bytes. Four of them, their separators and
/// `IDN ` take at most 103 bytes, inside [`crate::MAX_LINE_CONTENT`].
pub const MAX_IDENTITY_FIELD_LEN: usize = 24;

/// The longest error text of an `ERR` reply, bytes. `ERR <code> ` and the text take at most 106 bytes.
pub const MAX_ERROR_TEXT_LEN: usize = 100;

fn validate(text: &str, what: &'static str, max_len: usize, allow_comma: bool) -> Result<(), LdvProtocolError> {
    let invalid = |reason| Err(LdvProtocolError::InvalidText { what, reason });
    if text.len() > max_len {
        return invalid("too long");
    }
    if !text.bytes().all(|b| (0x20..=0x7e).contains(&b)) {
        return invalid("not printable ASCII");
    }
    if !allow_comma && text.contains(',') {
        return invalid("contains a comma, the field separator");
    }
    if text.starts_with(' ') || text.ends_with(' ') {
        return invalid("leading or trailing space");
    }
    Ok(())
}

/// One field of the identity reply: 1 to [`MAX_IDENTITY_FIELD_LEN`] bytes of printable ASCII, no comma, no leading
/// or trailing space (for example `Ometron`, `8330`, `SN04512`, `2.14`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct IdentityField(String);

impl IdentityField {
    /// Checks and wraps `text`.
    ///
    /// # Errors
    /// [`LdvProtocolError::InvalidText`] for an empty or too long field, a comma, a character outside printable
    /// ASCII, or a leading or trailing space.
    pub fn new(text: &str) -> Result<Self, LdvProtocolError> {
        if text.is_empty() {
            return Err(LdvProtocolError::InvalidText { what: "identity field", reason: "empty" });
        }
        validate(text, "identity field", MAX_IDENTITY_FIELD_LEN, false)?;
        Ok(Self(text.to_owned()))
    }

    /// The text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for IdentityField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// The human-readable text of an `ERR` reply: 0 to [`MAX_ERROR_TEXT_LEN`] bytes of printable ASCII, no leading or
/// trailing space. The numeric code, not this text, is what a driver acts on.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct ErrorText(String);

impl ErrorText {
    /// Checks and wraps `text`.
    ///
    /// # Errors
    /// [`LdvProtocolError::InvalidText`] for a too long text, a character outside printable ASCII, or a leading or
    /// trailing space.
    pub fn new(text: &str) -> Result<Self, LdvProtocolError> {
        validate(text, "error text", MAX_ERROR_TEXT_LEN, true)?;
        Ok(Self(text.to_owned()))
    }

    /// Makes a valid error text out of any string: characters outside printable ASCII become `?`, the text is cut
    /// to [`MAX_ERROR_TEXT_LEN`] bytes and trimmed. For building `ERR` replies from arbitrary messages.
    pub fn lossy(text: &str) -> Self {
        let printable: String =
            text.chars().map(|c| if (' '..='~').contains(&c) { c } else { '?' }).take(MAX_ERROR_TEXT_LEN).collect();
        Self(printable.trim_matches(' ').to_owned())
    }

    /// The text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for ErrorText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_field_length_limits() {
        assert!(IdentityField::new("").is_err());
        assert_eq!(IdentityField::new("x").unwrap().as_str(), "x");
        let longest = "a".repeat(MAX_IDENTITY_FIELD_LEN);
        assert_eq!(IdentityField::new(&longest).unwrap().as_str(), longest);
        assert!(IdentityField::new(&"a".repeat(MAX_IDENTITY_FIELD_LEN + 1)).is_err());
    }

    #[test]
    fn identity_field_character_rules() {
        assert!(IdentityField::new("Ometron Ltd").is_ok());
        assert!(IdentityField::new("~!@#$%^&*()_+{}|:\"<>?").is_ok());
        for bad in ["a,b", " a", "a ", "a\tb", "a\rb", "caf\u{e9}", "\u{7f}"] {
            assert!(matches!(IdentityField::new(bad), Err(LdvProtocolError::InvalidText { .. })), "{bad:?}");
        }
    }

    #[test]
    fn error_text_limits() {
        assert_eq!(ErrorText::new("").unwrap().as_str(), "");
        assert!(ErrorText::new("x = 1, y = 2").is_ok());
        assert!(ErrorText::new(&"e".repeat(MAX_ERROR_TEXT_LEN)).is_ok());
        assert!(ErrorText::new(&"e".repeat(MAX_ERROR_TEXT_LEN + 1)).is_err());
        assert!(ErrorText::new(" e").is_err());
        assert!(ErrorText::new("e\n").is_err());
    }

    #[test]
    fn lossy_always_gives_a_valid_text() {
        let long = format!("  caf\u{e9}\u{0}{}  ", "z".repeat(2 * MAX_ERROR_TEXT_LEN));
        let text = ErrorText::lossy(&long);
        assert_eq!(ErrorText::new(text.as_str()).unwrap(), text);
        assert!(text.as_str().starts_with("caf??z"));
        assert_eq!(text.as_str().len(), MAX_ERROR_TEXT_LEN - 2);
        assert_eq!(ErrorText::lossy("   ").as_str(), "");
    }
}
