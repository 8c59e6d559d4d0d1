//! The DAQ decoder check, generic over the direction (host-side `DeviceMessage` or device-side `HostCommand`):
//! no panic; after draining, less than one maximum frame buffered; chunking does not change what is decoded (errors
//! included); every decoded message re-encodes within `MAX_FRAME_LEN` to bytes that decode back to the same frame.

use std::fmt::Debug;

use metaplate_daq_protocol::{Decoder, MAX_FRAME_LEN, Message, encode};

use crate::chunks;

pub fn check<M: Message + Clone + Debug + PartialEq>(data: &[u8]) {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut Decoder::<M>::new(),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| d.decoded().collect(),
        |d| d.buffered_len() < MAX_FRAME_LEN,
    );
    let mut whole = Decoder::<M>::new();
    whole.push(payload);
    let at_once: Vec<_> = whole.decoded().collect();
    assert_eq!(chunked, at_once);

    for frame in chunked.into_iter().flatten() {
        let bytes = encode(frame.seq, &frame.message).expect("a decoded message re-encodes");
        assert!(bytes.len() <= MAX_FRAME_LEN);
        let mut again = Decoder::<M>::new();
        again.push(&bytes);
        assert_eq!(again.poll(), Some(Ok(frame)));
        assert_eq!(again.poll(), None);
    }
}
