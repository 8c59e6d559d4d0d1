//! The dialects of the byte devices: what their protocols let a replay do after an injected fault.

use crate::engine::Dialect;

/// A Polytec controller's line syntax: requests must match byte for byte (every request is absolute, and the
/// driver resends it unchanged after a miss); nothing is made up (the syntax has no resynchronisation command of its
/// own: the driver discards what is waiting and sends again).
#[derive(Debug, Clone, Copy, Default)]
pub struct PolytecDialect;

impl Dialect for PolytecDialect {
    fn matches(&mut self, recorded: &[u8], got: &[u8], _recovering: bool) -> Result<(), Vec<u8>> {
        if recorded == got { Ok(()) } else { Err(got.to_vec()) }
    }

    fn synthesize(&mut self, _got: &[u8]) -> Option<Vec<u8>> {
        None
    }

    fn translate_read(&self, recorded: &[u8]) -> Vec<u8> {
        recorded.to_vec()
    }
}

/// The LabJack U6's low-level functions: a command carries no per-attempt field (no sequence number; its
/// checksums depend on its bytes alone), so a resent command is byte for byte the recorded one and every command
/// must match exactly; nothing is made up or rewritten (the U6 has no resynchronisation command: the driver drains
/// the response endpoint and sends again).
#[derive(Debug, Clone, Copy, Default)]
pub struct U6Dialect;

impl Dialect for U6Dialect {
    fn matches(&mut self, recorded: &[u8], got: &[u8], _recovering: bool) -> Result<(), Vec<u8>> {
        if recorded == got { Ok(()) } else { Err(got.to_vec()) }
    }

    fn synthesize(&mut self, _got: &[u8]) -> Option<Vec<u8>> {
        None
    }

    fn translate_read(&self, recorded: &[u8]) -> Vec<u8> {
        recorded.to_vec()
    }
}
