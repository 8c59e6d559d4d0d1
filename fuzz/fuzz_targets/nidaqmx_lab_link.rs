//! Both sides of the NI-DAQmx stand-in's lab link (`nidaqmx_standin::lab`): arbitrary bytes as the request lines a
//! stand-in rig reads from a client (`read_line`, then `Request::parse`), and as the replies the stand-in reads
//! from a rig (`Reply::read_from`, asking for a data length from the first byte).
//!
//! Asserts: no panic; a line is never longer than its bound; every request parsed re-encodes to a line that parses
//! back to the same request; a data reply carries exactly the values asked for.

#![no_main]

use libfuzzer_sys::fuzz_target;
use nidaqmx_standin::lab::{MAX_READ_SAMPLES, Reply, Request, read_line};

fuzz_target!(|data: &[u8]| {
    let mut lines = data;
    while let Ok(line) = read_line(&mut lines) {
        assert!(line.len() <= 512, "a line of {} bytes", line.len());
        if let Ok(request) = Request::parse(&line) {
            if let Request::Read { count, .. } = request {
                assert!(count <= MAX_READ_SAMPLES);
            }
            let again = request.line();
            assert_eq!(Request::parse(again.trim_end_matches('\n')), Ok(request));
        }
    }
    let Some((&values, reply)) = data.split_first() else { return };
    if let Ok(Reply::Data(read)) = Reply::read_from(&mut &reply[..], usize::from(values)) {
        assert_eq!(read.len(), usize::from(values));
    }
});
