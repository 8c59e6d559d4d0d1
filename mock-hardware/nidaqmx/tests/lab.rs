//! The lab link (`nidaqmx_standin::lab`): its protocol both ways, hostile requests refused by name, the library's
//! own file found in a maps text, and a timed input task reading a lab (a fake one here, answering on a socket in
//! the test's folder) with the lab's pacing and its overflow.

use std::io::{BufReader, Write};
use std::os::unix::net::UnixListener;
use std::time::Instant;

use nidaqmx_standin::device::{VAL_CONT_SAMPS, VAL_GROUP_BY_SCAN_NUMBER, VAL_RISING, VAL_RSE, VAL_VOLTS, codes};
use nidaqmx_standin::lab::{MAX_READ_SAMPLES, Reply, Request, library_holding, read_line};
use nidaqmx_standin::{ReadOutcome, StandIn};

#[test]
fn requests_and_replies_read_back_as_written() {
    for request in [
        Request::Start { rate_hz: 24_000.0, inputs: vec![0, 1] },
        Request::Start { rate_hz: 1.0, inputs: vec![15] },
        Request::Outputs { x_v: -9.999_999_9, y_v: 0.1 },
        Request::Read { first: 0, count: 0 },
        Request::Read { first: u64::MAX, count: MAX_READ_SAMPLES },
    ] {
        let line = request.line();
        assert_eq!(Request::parse(line.trim_end_matches('\n')), Ok(request.clone()), "{line}");
    }
    for (reply, values) in [
        (Reply::Ok, 0),
        (Reply::Wait { ms: 7 }, 0),
        (Reply::Overrun, 0),
        (Reply::Data(vec![1.5, -0.25, f64::MIN_POSITIVE, 9.75]), 4),
        (Reply::Error("two\nlines".into()), 0),
    ] {
        let mut bytes = Vec::new();
        reply.write_to(&mut bytes).unwrap();
        let back = Reply::read_from(&mut bytes.as_slice(), values).unwrap();
        let expected = match reply {
            // An error is one line: its newlines become spaces.
            Reply::Error(text) => Reply::Error(text.replace('\n', " ")),
            other => other,
        };
        assert_eq!(back, expected);
    }
}

#[test]
fn hostile_requests_and_replies_are_refused_by_name() {
    for (line, says) in [
        ("", "is not `start"),
        ("stop now", "is not `start"),
        ("start 24000", "is not `start"),
        ("start NaN 0", "not within"),
        ("start -1 0", "not within"),
        ("start 1e-300 0", "not within"),
        ("start inf 0", "not within"),
        ("outputs 1.0 NaN", "not a finite number"),
        ("outputs 1.0", "is not `start"),
        ("start 24000 0,x", "not an ai index"),
        ("start 24000 0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16", "17 inputs"),
        ("start 24000 300", "not an ai index"),
        ("read 0 99999999999", "over"),
        ("read -1 5", "not a count"),
        ("read 0 5 6", "too many words"),
    ] {
        let error = Request::parse(line).unwrap_err();
        assert!(error.contains(says), "{line:?}: {error}");
    }
    let long = vec![b'x'; 4096];
    let error = read_line(&mut long.as_slice()).unwrap_err();
    assert_eq!(error.kind(), std::io::ErrorKind::InvalidData);
    assert_eq!(read_line(&mut &b""[..]).unwrap_err().kind(), std::io::ErrorKind::UnexpectedEof);
    for bytes in [&b"wait soon\n"[..], b"hello\n", b"data\n\x01\x02"] {
        assert!(Reply::read_from(&mut &bytes[..], 1).is_err(), "{bytes:?}");
    }
}

#[test]
fn the_library_is_the_mapping_that_holds_its_code() {
    let maps = "7f0000000000-7f0000001000 r-xp 00000000 08:01 42                         /lab dir/libnidaqmx_standin.so\n\
                7f0000001000-7f0000002000 rw-p 00000000 00:00 0 \n\
                7f0000002000-7f0000003000 r--p 00000000 00:00 0                          [vdso]\n";
    assert_eq!(library_holding(maps, 0x7f00_0000_0800).unwrap().to_str(), Some("/lab dir/libnidaqmx_standin.so"));
    assert_eq!(library_holding(maps, 0x7f00_0000_1800), None, "an anonymous mapping");
    assert_eq!(library_holding(maps, 0x7f00_0000_2800), None, "not a file");
    assert_eq!(library_holding(maps, 0x10), None);
}

/// A fake lab at `socket`: one acquisition of two inputs at 1 kHz; each read first waits once, then gets sample
/// `n` of input `c` as `n + c / 10` V; a read from sample 100 on finds the buffer overflowed.
fn fake_lab(socket: &std::path::Path) -> std::thread::JoinHandle<Vec<String>> {
    let listener = UnixListener::bind(socket).unwrap();
    std::thread::spawn(move || {
        let (stream, _) = listener.accept().unwrap();
        let mut reader = BufReader::new(stream.try_clone().unwrap());
        let mut writer = stream;
        let mut heard = Vec::new();
        let mut waited = false;
        while let Ok(line) = read_line(&mut reader) {
            heard.push(line.clone());
            let reply = match Request::parse(&line).unwrap() {
                Request::Start { .. } => Reply::Ok,
                Request::Read { .. } if !waited => {
                    waited = true;
                    Reply::Wait { ms: 3 }
                }
                Request::Read { first, .. } if first >= 100 => Reply::Overrun,
                Request::Read { first, count } => {
                    waited = false;
                    Reply::Data((first..first + count).flat_map(|n| [n as f64, n as f64 + 0.1]).collect())
                }
                Request::Outputs { .. } => Reply::Ok,
            };
            reply.write_to(&mut writer).unwrap();
            writer.flush().unwrap();
        }
        heard
    })
}

#[test]
fn a_timed_input_reads_the_lab_at_its_pace_within_its_range_and_an_overflow_is_200279() {
    let dir = tempfile::tempdir().unwrap();
    let socket = dir.path().join("lab.sock");
    let lab = fake_lab(&socket);
    let mut ni = StandIn::new();
    ni.set_lab_socket(Some(socket));
    let task = ni.create_task("ai").unwrap();
    // ai0 on +/-1 V: the lab's values above 1 V are clipped, as the device's converter does.
    ni.create_ai_voltage_chan(task, "Dev1/ai0:1", VAL_RSE, -1.0, 1.0, VAL_VOLTS).unwrap();
    ni.cfg_samp_clk_timing(task, "", 1_000.0, VAL_RISING, VAL_CONT_SAMPS, 1_000).unwrap();
    let now = Instant::now();
    ni.start(task, now).unwrap();
    let mut out = vec![0.0; 100];
    // The lab asks for patience first: the stand-in waits (the read loop sleeps until then).
    assert!(
        matches!(ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now).unwrap(), ReadOutcome::Wait(Some(t)) if t > now)
    );
    assert_eq!(ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now).unwrap(), ReadOutcome::Done(50));
    assert_eq!(&out[..6], &[0.0, 0.1, 1.0, 1.0, 1.0, 1.0]);
    assert!(matches!(ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now).unwrap(), ReadOutcome::Wait(_)));
    assert_eq!(ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now).unwrap(), ReadOutcome::Done(50));
    // Samples 100 on: the lab's buffer overflowed, NI's -200279.
    let _ = ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now);
    let error = ni.try_read(task, 50, VAL_GROUP_BY_SCAN_NUMBER, &mut out, now).unwrap_err();
    assert_eq!(error.code, codes::SAMPLES_NO_LONGER_AVAILABLE, "{}", error.message);
    // Stopping hangs up: the lab heard the start and the reads, from sample 0, in order.
    ni.stop(task, now).unwrap();
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || done_tx.send(lab.join().unwrap()));
    let heard = done_rx.recv_timeout(std::time::Duration::from_secs(10)).expect("the stop hangs up on the lab");
    assert_eq!(heard[0], "start 1000 0,1");
    assert_eq!(&heard[1..5], ["read 0 50", "read 0 50", "read 50 50", "read 50 50"]);
}

#[test]
fn a_lab_that_is_gone_is_a_device_that_cannot_be_accessed() {
    let dir = tempfile::tempdir().unwrap();
    let mut ni = StandIn::new();
    ni.set_lab_socket(Some(dir.path().join("lab.sock")));
    let task = ni.create_task("ai").unwrap();
    ni.create_ai_voltage_chan(task, "Dev1/ai0", VAL_RSE, -1.0, 1.0, VAL_VOLTS).unwrap();
    ni.cfg_samp_clk_timing(task, "", 1_000.0, VAL_RISING, VAL_CONT_SAMPS, 1_000).unwrap();
    let error = ni.start(task, Instant::now()).unwrap_err();
    assert_eq!(error.code, codes::DEVICE_CANNOT_BE_ACCESSED, "{}", error.message);
    assert!(error.message.contains("stand-in rig"), "{}", error.message);
}

#[test]
fn on_demand_output_writes_are_told_to_the_lab_with_both_outputs() {
    use nidaqmx_standin::device::VAL_GROUP_BY_CHANNEL;
    let dir = tempfile::tempdir().unwrap();
    let socket = dir.path().join("lab.sock");
    let lab = fake_lab(&socket);
    let mut ni = StandIn::new();
    ni.set_lab_socket(Some(socket));
    let task = ni.create_task("mirrors").unwrap();
    ni.create_ao_voltage_chan(task, "Dev1/ao0:1", -10.0, 10.0, VAL_VOLTS).unwrap();
    // One sample per output, written at once (auto-start), as the galvo outputs backend moves the mirrors.
    ni.write_analog_f64(task, 1, true, VAL_GROUP_BY_CHANNEL, &[1.5, -2.25], Instant::now()).unwrap();
    ni.write_analog_f64(task, 1, true, VAL_GROUP_BY_CHANNEL, &[0.0, 9.5], Instant::now()).unwrap();
    ni.clear(task, Instant::now()).unwrap();
    drop(ni);
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || done_tx.send(lab.join().unwrap()));
    let heard = done_rx.recv_timeout(std::time::Duration::from_secs(10)).expect("dropping the stand-in hangs up");
    assert_eq!(heard, ["outputs 1.5 -2.25", "outputs 0.0 9.5"]);
}
