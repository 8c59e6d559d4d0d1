//! Little-endian field readers and writers shared by the payload codecs.

use crate::error::DaqError;

/// Reads fields from one payload front to back; every read checks the remaining length, so a short payload is a
/// [`DaqError::BadPayloadLength`], never a panic.
pub(crate) struct Reader<'a> {
    message: &'static str,
    payload: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(message: &'static str, payload: &'a [u8]) -> Self {
        Self { message, payload, pos: 0 }
    }

    fn short(&self, needed: usize) -> DaqError {
        DaqError::BadPayloadLength {
            message: self.message,
            len: self.payload.len(),
            expected: format!("at least {} bytes", self.pos.saturating_add(needed)),
        }
    }

    pub(crate) fn bytes(&mut self, n: usize) -> Result<&'a [u8], DaqError> {
        let end = self.pos.checked_add(n).filter(|&end| end <= self.payload.len()).ok_or_else(|| self.short(n))?;
        let out = &self.payload[self.pos..end];
        self.pos = end;
        Ok(out)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], DaqError> {
        let mut out = [0; N];
        out.copy_from_slice(self.bytes(N)?);
        Ok(out)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, DaqError> {
        Ok(self.array::<1>()?[0])
    }

    pub(crate) fn u16(&mut self) -> Result<u16, DaqError> {
        Ok(u16::from_le_bytes(self.array()?))
    }

    pub(crate) fn u32(&mut self) -> Result<u32, DaqError> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    pub(crate) fn u64(&mut self) -> Result<u64, DaqError> {
        Ok(u64::from_le_bytes(self.array()?))
    }

    /// A text field: a u8 byte length, then that many bytes of UTF-8.
    pub(crate) fn text(&mut self, field: &'static str) -> Result<String, DaqError> {
        let len = usize::from(self.u8()?);
        let bytes = self.bytes(len)?;
        String::from_utf8(bytes.to_vec()).map_err(|_| DaqError::InvalidUtf8 { message: self.message, field })
    }

    /// Checks that the whole payload was read: trailing bytes are a length error, not silently ignored.
    pub(crate) fn finish(self) -> Result<(), DaqError> {
        if self.pos == self.payload.len() {
            Ok(())
        } else {
            Err(DaqError::BadPayloadLength {
                message: self.message,
                len: self.payload.len(),
                expected: format!("{} bytes", self.pos),
            })
        }
    }
}

pub(crate) fn put_u16(out: &mut Vec<u8>, v: u16) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// Writes a text field (u8 length, UTF-8 bytes).
///
/// # Errors
/// [`DaqError::Unencodable`] if the text is longer than 255 bytes.
pub(crate) fn put_text(
    out: &mut Vec<u8>,
    message: &'static str,
    field: &'static str,
    text: &str,
) -> Result<(), DaqError> {
    let len = u8::try_from(text.len()).map_err(|_| DaqError::Unencodable {
        message,
        reason: format!("{field} is {} bytes of UTF-8, more than {}", text.len(), crate::MAX_TEXT_LEN),
    })?;
    out.push(len);
    out.extend_from_slice(text.as_bytes());
    Ok(())
}

/// Converts a count to the u8 the wire carries.
pub(crate) fn count_u8(message: &'static str, what: &'static str, n: usize, max: usize) -> Result<u8, DaqError> {
    if n > max {
        return Err(DaqError::Unencodable { message, reason: format!("{n} {what}, more than the maximum of {max}") });
    }
    u8::try_from(n).map_err(|_| DaqError::Unencodable { message, reason: format!("{n} {what} do not fit a u8") })
}
