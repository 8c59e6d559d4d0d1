//! A small, stable, non-cryptographic hash for cache keys and scene identities.

/// FNV-1a, 64 bits, over `bytes`: the same value on every machine, run and Rust version (unlike `std`'s hashers),
/// which is what cache keys and scene hashes need. Not for integrity checks (the store uses SHA-256 for those).
pub fn fnv1a_64(bytes: impl IntoIterator<Item = u8>) -> u64 {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    bytes.into_iter().fold(OFFSET, |h, b| (h ^ u64::from(b)).wrapping_mul(PRIME))
}
