//! The U6's two packet checksums (User's Guide section 5.1, "Command/Response"; LabJackPython `setChecksum8`,
//! `setChecksum16`, `setChecksum` in `LabJackPython.py`).
//!
//! - Checksum8 (byte 0): the sum of the bytes it covers, folded twice (`(s & 0xff) + (s >> 8)`, then again), so the
//!   result is one byte. A normal command covers bytes `1..len`; an extended command covers bytes `1..6`.
//! - Checksum16 (bytes 4-5, little-endian): the plain sum of bytes `6..len`, modulo 2^16. Extended commands only.
//!
//! A packet is extended when bits 3-6 of its command byte (byte 1) are all set (`0xF8` and `0xF9`).

/// Whether `command_byte` (byte 1 of a packet) marks an extended command, which carries a Checksum16.
pub fn is_extended(command_byte: u8) -> bool {
    command_byte & 0x78 == 0x78
}

/// Checksum8 of `covered` (the bytes after byte 0 it covers).
pub fn checksum8(covered: &[u8]) -> u8 {
    let sum: u32 = covered.iter().map(|&b| u32::from(b)).sum();
    let once = (sum & 0xff) + (sum >> 8);
    // Folding twice always fits a byte: `once` is at most 0xff + 0xff_ffff >> 8 for any packet the U6 sends.
    ((once & 0xff) + (once >> 8)) as u8
}

/// Checksum16 of `covered` (bytes 6 onwards of an extended packet).
pub fn checksum16(covered: &[u8]) -> u16 {
    covered.iter().fold(0u16, |sum, &b| sum.wrapping_add(u16::from(b)))
}

/// Writes the checksums of `packet` in place: Checksum16 then Checksum8 for an extended packet (at least 6 bytes),
/// Checksum8 over the whole packet for a normal one (at least 2 bytes). Shorter packets are left as they are.
pub fn seal(packet: &mut [u8]) {
    if packet.len() >= 6 && is_extended(packet[1]) {
        let [lo, hi] = checksum16(&packet[6..]).to_le_bytes();
        packet[4] = lo;
        packet[5] = hi;
        packet[0] = checksum8(&packet[1..6]);
    } else if packet.len() >= 2 {
        packet[0] = checksum8(&packet[1..]);
    }
}

/// The checksums `packet` should carry, as (Checksum8, Checksum16 if extended), or `None` if it is too short to
/// hold them.
pub fn expected(packet: &[u8]) -> Option<(u8, Option<u16>)> {
    if packet.len() >= 6 && is_extended(packet[1]) {
        Some((checksum8(&packet[1..6]), Some(checksum16(&packet[6..]))))
    } else if packet.len() >= 2 && !is_extended(packet[1]) {
        Some((checksum8(&packet[1..]), None))
    } else {
        None
    }
}

/// Whether `packet` carries the checksums it should.
pub fn is_valid(packet: &[u8]) -> bool {
    match expected(packet) {
        Some((c8, Some(c16))) => packet[0] == c8 && u16::from_le_bytes([packet[4], packet[5]]) == c16,
        Some((c8, None)) => packet[0] == c8,
        None => false,
    }
}
