//! The input convention shared by the protocol fuzz targets: byte 0 gives the number of cuts (0 to 15), the next
//! bytes give each cut's position as a fraction of the payload (byte / 256), the rest is the payload. Included into
//! each target with `#[path = "common/chunks.rs"] mod chunks;`.

/// The payload and its chunk boundaries (sorted, ending at the payload's length); `None` for empty input.
pub fn split(data: &[u8]) -> Option<(&[u8], Vec<usize>)> {
    let (&head, rest) = data.split_first()?;
    let cut_count = usize::from(head % 16).min(rest.len());
    let (cut_bytes, payload) = rest.split_at(cut_count);
    let mut cuts: Vec<usize> = cut_bytes.iter().map(|&b| usize::from(b) * payload.len() / 256).collect();
    cuts.push(payload.len());
    cuts.sort_unstable();
    Some((payload, cuts))
}

/// Pushes `payload` into `decoder` chunk by chunk, draining after each push and checking the decoder's bound with
/// `bounded`; returns everything drained, in order.
pub fn feed<D, T>(
    decoder: &mut D,
    payload: &[u8],
    cuts: &[usize],
    mut push: impl FnMut(&mut D, &[u8]),
    mut drain: impl FnMut(&mut D) -> Vec<T>,
    mut bounded: impl FnMut(&D) -> bool,
) -> Vec<T> {
    let mut out = Vec::new();
    let mut start = 0;
    for &cut in cuts {
        push(decoder, &payload[start..cut]);
        start = cut;
        out.extend(drain(decoder));
        assert!(bounded(decoder), "decoder buffer above its documented bound");
    }
    out
}
