//! The mock controller served on a pseudo-terminal, so that the real serial transport (`SerialPortLine`) talks to
//! it exactly as to a USB adapter.

use std::os::unix::io::RawFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use nix::poll::{PollFd, PollFlags, poll};
use nix::sys::termios::{SetArg, cfmakeraw, tcgetattr, tcsetattr};

use crate::served::ServedDevice;

/// How long the server thread waits for host bytes before it looks at its stop flag, ms: bounds shutdown time.
const POLL_MS: i32 = 5;

/// Why the pseudo-terminal could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    /// A system call failed.
    #[error("pseudo-terminal {step}: {source}")]
    Sys {
        /// Which step.
        step: &'static str,
        /// The OS error.
        source: nix::Error,
    },
    /// The server thread could not be started.
    #[error("cannot start the pseudo-terminal server thread: {0}")]
    Thread(std::io::Error),
}

/// A mock device ([`crate::MockDevice`], or any [`ServedDevice`]) answering on a pseudo-terminal from a background
/// thread. Open [`PtyServer::path`] with the real serial transport. The thread stops (and the terminal closes) when the server is dropped.
///
/// A pseudo-terminal cannot vanish like a USB adapter, and the server cannot tell when the host reopens it: here a
/// disconnect fault loses its line (the host sees a timeout, not an I/O error), and the link comes back with the
/// next bytes the host sends (power-cycled if the fault says so). Disconnects proper are tested in process
/// ([`crate::MockLine`]).
#[derive(Debug)]
pub struct PtyServer {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    fds: [RawFd; 2],
}

impl PtyServer {
    /// Opens a pseudo-terminal pair in raw mode and serves `device` on it.
    ///
    /// # Errors
    /// [`PtyError`] when the terminal or the thread cannot be created.
    pub fn spawn<D: ServedDevice>(device: Arc<Mutex<D>>) -> Result<Self, PtyError> {
        let pair = nix::pty::openpty(None, None).map_err(|source| PtyError::Sys { step: "openpty", source })?;
        let fds = [pair.master, pair.slave];
        let setup = || -> Result<PathBuf, PtyError> {
            // Raw mode: no echo, no CR/LF translation, no line buffering; bytes pass as they are, as on RS-232.
            let mut termios = tcgetattr(pair.slave).map_err(|source| PtyError::Sys { step: "tcgetattr", source })?;
            cfmakeraw(&mut termios);
            tcsetattr(pair.slave, SetArg::TCSANOW, &termios)
                .map_err(|source| PtyError::Sys { step: "tcsetattr", source })?;
            nix::unistd::ttyname(pair.slave).map_err(|source| PtyError::Sys { step: "ttyname", source })
        };
        let path = match setup() {
            Ok(path) => path,
            Err(e) => {
                close_all(fds);
                return Err(e);
            }
        };
        let stop = Arc::new(AtomicBool::new(false));
        let thread_stop = Arc::clone(&stop);
        let master = pair.master;
        let thread =
            std::thread::Builder::new().name("mock-pty".into()).spawn(move || serve(master, &device, &thread_stop));
        match thread {
            Ok(thread) => Ok(Self { path, stop, thread: Some(thread), fds }),
            Err(e) => {
                close_all(fds);
                Err(PtyError::Thread(e))
            }
        }
    }

    /// The terminal's device path (for example `/dev/pts/3`), to open with the serial transport.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for PtyServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(thread) = self.thread.take() {
            // The thread looks at the flag every POLL_MS, so this join is bounded.
            let _ = thread.join();
        }
        close_all(self.fds);
    }
}

fn close_all(fds: [RawFd; 2]) {
    for fd in fds {
        let _ = nix::unistd::close(fd);
    }
}

/// Reads host bytes, feeds the device, writes its answers; until `stop` or an unrecoverable terminal error.
/// The slave side stays open in this process, so the master never sees a hang-up when the host closes and
/// reopens the port.
fn serve<D: ServedDevice>(master: RawFd, device: &Mutex<D>, stop: &AtomicBool) {
    let mut buf = [0u8; 512];
    while !stop.load(Ordering::Acquire) {
        let mut fds = [PollFd::new(master, PollFlags::POLLIN)];
        match poll(&mut fds, POLL_MS) {
            Ok(0) | Err(nix::errno::Errno::EINTR) => continue,
            Ok(_) => {}
            Err(_) => return,
        }
        let n = match nix::unistd::read(master, &mut buf) {
            Ok(n) => n,
            Err(nix::errno::Errno::EINTR | nix::errno::Errno::EAGAIN) => continue,
            Err(_) => return,
        };
        let output = {
            let Ok(mut device) = device.lock() else { return };
            if !device.is_connected() {
                // The host reopening the port is what brings a dropped link back; here, the next bytes it sends.
                device.reconnect();
            }
            device.receive(buf.get(..n).unwrap_or(&buf));
            device.take_output()
        };
        if write_all(master, &output, stop).is_err() {
            return;
        }
    }
}

/// Writes `bytes`, waiting for room in bounded polls so that a host that stopped reading cannot block shutdown.
fn write_all(fd: RawFd, mut bytes: &[u8], stop: &AtomicBool) -> nix::Result<()> {
    while !bytes.is_empty() {
        if stop.load(Ordering::Acquire) {
            return Ok(());
        }
        let mut fds = [PollFd::new(fd, PollFlags::POLLOUT)];
        if poll(&mut fds, POLL_MS)? == 0 {
            continue;
        }
        match nix::unistd::write(fd, bytes) {
            Ok(n) => bytes = bytes.get(n..).unwrap_or_default(),
            Err(nix::errno::Errno::EINTR | nix::errno::Errno::EAGAIN) => continue,
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
