//! The lab link: the stand-in's analog inputs read from a running stand-in rig (`metaplate lab serve`).
//!
//! When a Unix socket named [`SOCKET_NAME`] sits in the folder the library was loaded from (`lab serve` copies the
//! library into its folder and listens there), every timed analog-input task reads the mock lab's signals (the
//! vibrometer's output and the audio loopback as the lab renders them) instead of the built-in wiring, and the
//! voltages of on-demand output writes are told to the lab (its galvo mirrors follow them); timed outputs and
//! on-demand reads stay the stand-in's own. The lab paces the samples: a read waits until the lab has acquired
//! them, as it waits on a device; an input buffer that overflows is the lab's to report (`overrun`), not the
//! stand-in's clock's.
//!
//! The stand-in holds its state's lock while it waits for a reply (as it does for every call): another thread's
//! DAQmx call waits meanwhile, at most for the reply timeout.
//!
//! The protocol, one connection per started task, requests and replies as lines ending in `\n`:
//! - `start RATE_HZ INPUTS` (`INPUTS`: the `ai` indices, comma-separated, in the task's order) -> `ok`;
//! - `read FIRST COUNT` (samples per input, from the task's start) -> `wait MS` (not yet acquired: ask again
//!   after MS milliseconds), `data` followed by COUNT x inputs values, f64 little-endian, by scan, or `overrun`
//!   (the device's buffer overflowed: the stand-in reports -200279, as NI-DAQmx does);
//! - `outputs X_V Y_V` (a device's `ao0` and `ao1` after an on-demand write: the galvo mirrors' voltages) -> `ok`,
//!   on a connection of its own, which the stand-in opens at its first on-demand output write;
//! - any -> `error TEXT`.
//!
//! Both sides use this module, so there is one home for the encoding.

use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;

/// The socket's file name, in the folder of the loaded library.
pub const SOCKET_NAME: &str = "lab.sock";

/// Most samples per input one `read` may ask.
pub const MAX_READ_SAMPLES: u64 = 1 << 20;

/// Most values (samples times inputs) one `read` may ask: a bound on what a hostile request makes the lab
/// allocate (8 MiB).
pub const MAX_READ_VALUES: u64 = 1 << 20;

/// The rates a `start` may ask, Hz (the USB-6211's 250 kS/s is well inside).
pub const RATE_RANGE_HZ: (f64, f64) = (1.0, 1e7);

/// Most inputs one `start` may name (the USB-6211's 16).
pub const MAX_INPUTS: usize = 16;

/// Longest request or reply line, bytes.
const MAX_LINE_BYTES: u64 = 512;

/// How long the stand-in waits for one reply before it reports the lab gone, s.
const REPLY_TIMEOUT_S: u64 = 10;

/// What the stand-in asks the lab.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// An acquisition starts now at `rate_hz`, on these inputs.
    Start {
        /// Sample rate, Hz.
        rate_hz: f64,
        /// `ai` indices, in the task's channel order.
        inputs: Vec<u8>,
    },
    /// Samples `first .. first + count` of each input.
    Read {
        /// First sample, counted from the acquisition's start.
        first: u64,
        /// Samples per input.
        count: u64,
    },
    /// The two analog outputs now hold these voltages.
    Outputs {
        /// `ao0`, V.
        x_v: f64,
        /// `ao1`, V.
        y_v: f64,
    },
}

impl Request {
    /// The request's line, `\n` included.
    pub fn line(&self) -> String {
        match self {
            Request::Start { rate_hz, inputs } => {
                let inputs: Vec<String> = inputs.iter().map(u8::to_string).collect();
                format!("start {rate_hz} {}\n", inputs.join(","))
            }
            Request::Read { first, count } => format!("read {first} {count}\n"),
            Request::Outputs { x_v, y_v } => format!("outputs {x_v:?} {y_v:?}\n"),
        }
    }

    /// Parses one request line (without its `\n`).
    ///
    /// # Errors
    /// What is wrong with it: an unknown verb, a missing or bad number, a rate outside [`RATE_RANGE_HZ`], no
    /// input or more than [`MAX_INPUTS`], a count above [`MAX_READ_SAMPLES`], a voltage that is not finite.
    pub fn parse(line: &str) -> Result<Request, String> {
        let mut words = line.split_whitespace();
        let verb = words.next().unwrap_or("");
        let (a, b) = (words.next(), words.next());
        if words.next().is_some() {
            return Err(format!("{line:?}: too many words"));
        }
        match (verb, a, b) {
            ("start", Some(rate), Some(inputs)) => {
                let rate_hz: f64 = rate.parse().map_err(|_| format!("rate {rate:?} is not a number"))?;
                if !(RATE_RANGE_HZ.0..=RATE_RANGE_HZ.1).contains(&rate_hz) {
                    return Err(format!(
                        "rate {rate_hz} Hz is not within {} to {} Hz",
                        RATE_RANGE_HZ.0, RATE_RANGE_HZ.1
                    ));
                }
                let inputs = inputs
                    .split(',')
                    .map(|i| i.parse::<u8>().map_err(|_| format!("input {i:?} is not an ai index")))
                    .collect::<Result<Vec<u8>, String>>()?;
                if inputs.is_empty() || inputs.len() > MAX_INPUTS {
                    return Err(format!("{} inputs: 1 to {MAX_INPUTS}", inputs.len()));
                }
                Ok(Request::Start { rate_hz, inputs })
            }
            ("read", Some(first), Some(count)) => {
                let first = first.parse().map_err(|_| format!("first sample {first:?} is not a count"))?;
                let count: u64 = count.parse().map_err(|_| format!("count {count:?} is not a count"))?;
                if count > MAX_READ_SAMPLES {
                    return Err(format!("count {count} is over {MAX_READ_SAMPLES}"));
                }
                Ok(Request::Read { first, count })
            }
            ("outputs", Some(x), Some(y)) => {
                let volts = |v: &str| match v.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(format!("output voltage {v:?} is not a finite number")),
                };
                Ok(Request::Outputs { x_v: volts(x)?, y_v: volts(y)? })
            }
            _ => Err(format!("{line:?} is not `start RATE INPUTS`, `read FIRST COUNT` or `outputs X_V Y_V`")),
        }
    }
}

/// What the lab answers.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// The acquisition started.
    Ok,
    /// The samples are not acquired yet: ask again after this many milliseconds.
    Wait {
        /// Milliseconds.
        ms: u64,
    },
    /// The samples, by scan (sample `i` of input `c` at `i * inputs + c`), volts.
    Data(Vec<f64>),
    /// The device's input buffer overflowed before these samples were read: they are gone.
    Overrun,
    /// The request failed, and why.
    Error(String),
}

impl Reply {
    /// Writes the reply.
    ///
    /// # Errors
    /// The stream's.
    pub fn write_to(&self, out: &mut impl Write) -> std::io::Result<()> {
        match self {
            Reply::Ok => out.write_all(b"ok\n"),
            Reply::Overrun => out.write_all(b"overrun\n"),
            Reply::Wait { ms } => out.write_all(format!("wait {ms}\n").as_bytes()),
            Reply::Data(values) => {
                out.write_all(b"data\n")?;
                // In pieces of 64 KiB: no second copy of a large reply.
                for chunk in values.chunks(8192) {
                    let bytes: Vec<u8> = chunk.iter().flat_map(|v| v.to_le_bytes()).collect();
                    out.write_all(&bytes)?;
                }
                Ok(())
            }
            // One line: a newline in the text would end the reply early.
            Reply::Error(text) => out.write_all(format!("error {}\n", text.replace('\n', " ")).as_bytes()),
        }?;
        out.flush()
    }

    /// Reads one reply; a `data` reply carries `values` values.
    ///
    /// # Errors
    /// The stream's; `InvalidData` for a line that is no reply; `UnexpectedEof` when the lab hung up.
    pub fn read_from(input: &mut impl BufRead, values: usize) -> std::io::Result<Reply> {
        let line = read_line(input)?;
        let invalid = |what: String| std::io::Error::new(std::io::ErrorKind::InvalidData, what);
        match line.split_once(' ').unwrap_or((line.as_str(), "")) {
            ("ok", "") => Ok(Reply::Ok),
            ("overrun", "") => Ok(Reply::Overrun),
            ("wait", ms) => Ok(Reply::Wait { ms: ms.parse().map_err(|_| invalid(format!("bad wait {ms:?}")))? }),
            ("data", "") => {
                // What was asked, never more than a read may ask: a rogue socket cannot make this allocate more.
                if values as u64 > MAX_READ_VALUES {
                    return Err(invalid(format!("{values} values is over {MAX_READ_VALUES}")));
                }
                let mut bytes = vec![0_u8; values * 8];
                input.read_exact(&mut bytes)?;
                Ok(Reply::Data(
                    bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))).collect(),
                ))
            }
            ("error", text) => Ok(Reply::Error(text.to_owned())),
            _ => Err(invalid(format!("{line:?} is not a reply"))),
        }
    }
}

/// One line without its `\n`, at most [`MAX_LINE_BYTES`].
///
/// # Errors
/// `UnexpectedEof` at the end of the stream; `InvalidData` for a line too long or not UTF-8.
pub fn read_line(input: &mut impl BufRead) -> std::io::Result<String> {
    let mut bytes = Vec::new();
    input.take(MAX_LINE_BYTES + 1).read_until(b'\n', &mut bytes)?;
    if bytes.is_empty() {
        return Err(std::io::ErrorKind::UnexpectedEof.into());
    }
    if bytes.pop() != Some(b'\n') {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, "line too long or cut short"));
    }
    String::from_utf8(bytes).map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "line not UTF-8"))
}

/// A started task's connection to the lab.
#[derive(Debug)]
pub struct LabLink {
    stream: BufReader<UnixStream>,
    inputs: usize,
}

impl LabLink {
    /// Connects to the lab at `socket` and starts an acquisition of `inputs` at `rate_hz`.
    ///
    /// # Errors
    /// Why the lab cannot be reached, or its `error` reply.
    pub fn start(socket: &Path, rate_hz: f64, inputs: &[u8]) -> Result<LabLink, String> {
        let mut link = LabLink::connect(socket, inputs.len())?;
        let gone = |e: std::io::Error| format!("the stand-in rig at {}: {e}", socket.display());
        match link.ask(&Request::Start { rate_hz, inputs: inputs.to_vec() }, 0).map_err(gone)? {
            Reply::Ok => Ok(link),
            Reply::Error(text) => Err(format!("the stand-in rig: {text}")),
            other => Err(format!("the stand-in rig answered {other:?} to start")),
        }
    }

    /// Connects to the lab at `socket` for output voltages ([`LabLink::set_outputs`]).
    ///
    /// # Errors
    /// Why the lab cannot be reached.
    pub fn outputs(socket: &Path) -> Result<LabLink, String> {
        LabLink::connect(socket, 0)
    }

    /// A connection to the lab at `socket` whose `data` replies carry `inputs` values per sample.
    fn connect(socket: &Path, inputs: usize) -> Result<LabLink, String> {
        let gone = |e: std::io::Error| format!("the stand-in rig at {}: {e}", socket.display());
        let stream = UnixStream::connect(socket).map_err(gone)?;
        stream.set_read_timeout(Some(Duration::from_secs(REPLY_TIMEOUT_S))).map_err(gone)?;
        Ok(LabLink { stream: BufReader::new(stream), inputs })
    }

    /// Tells the lab the outputs now hold `x_v` (`ao0`) and `y_v` (`ao1`).
    ///
    /// # Errors
    /// Why the lab cannot be reached, or its `error` reply.
    pub fn set_outputs(&mut self, x_v: f64, y_v: f64) -> Result<(), String> {
        match self.ask(&Request::Outputs { x_v, y_v }, 0).map_err(|e| format!("the stand-in rig: {e}"))? {
            Reply::Ok => Ok(()),
            Reply::Error(text) => Err(format!("the stand-in rig: {text}")),
            other => Err(format!("the stand-in rig answered {other:?} to outputs")),
        }
    }

    /// Asks for samples `first .. first + count` of each input.
    ///
    /// # Errors
    /// Why the lab cannot be reached.
    pub fn read(&mut self, first: u64, count: u64) -> std::io::Result<Reply> {
        let values = usize::try_from(count).unwrap_or(usize::MAX).saturating_mul(self.inputs);
        self.ask(&Request::Read { first, count }, values)
    }

    fn ask(&mut self, request: &Request, values: usize) -> std::io::Result<Reply> {
        self.stream.get_mut().write_all(request.line().as_bytes())?;
        Reply::read_from(&mut self.stream, values)
    }
}

/// The lab's socket beside the loaded library, if one is there: the library's own file is found in
/// `/proc/self/maps` as the mapping that holds this function's code.
pub fn socket_beside_library() -> Option<PathBuf> {
    static FOUND: OnceLock<Option<PathBuf>> = OnceLock::new();
    FOUND
        .get_or_init(|| {
            let address = socket_beside_library as fn() -> Option<PathBuf> as usize;
            let maps = std::fs::read_to_string("/proc/self/maps").ok()?;
            let library = library_holding(&maps, address)?;
            let socket = library.parent()?.join(SOCKET_NAME);
            socket.exists().then_some(socket)
        })
        .clone()
}

/// The file mapped at `address` in a `/proc/self/maps` text (its sixth field on, which may hold spaces).
pub fn library_holding(maps: &str, address: usize) -> Option<PathBuf> {
    maps.lines().find_map(|line| {
        let mut rest = line.trim_start();
        let mut fields = Vec::with_capacity(5);
        for _ in 0..5 {
            let (field, tail) = rest.split_once(char::is_whitespace)?;
            fields.push(field);
            rest = tail.trim_start();
        }
        let (lo, hi) = fields[0].split_once('-')?;
        let (lo, hi) = (usize::from_str_radix(lo, 16).ok()?, usize::from_str_radix(hi, 16).ok()?);
        ((lo..hi).contains(&address) && rest.starts_with('/')).then(|| PathBuf::from(rest.trim_end()))
    })
}
