//! `LdvDriver`: the [`Vibrometer`] capability over the LDV controller's serial protocol.

use std::sync::Arc;
use std::time::{Duration, Instant};

use metaplate_core::clock::Clock;
use metaplate_core::vibrometer::{Tracking, VelocityScale, Vibrometer, VibrometerError, VibrometerIdentity};
use metaplate_ldv_protocol::{
    Command, ErrorCode, LaserState, LdvProtocolError, PlatePoint, REPLY_TIMEOUT_S, Reply, ReplyDecoder, SyncToken,
    TrackingFilter, VelocityRange, encode_command,
};

use crate::line::{LineError, SerialLine};
use crate::policy::RetryPolicy;

/// The settings made through the driver, re-applied after a reconnect (the controller may have been power-cycled).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AppliedSettings {
    /// The last velocity range set, if any.
    pub velocity_range: Option<VelocityRange>,
    /// The last tracking filter set, if any.
    pub tracking: Option<TrackingFilter>,
    /// The last laser state set, if any.
    pub laser: Option<LaserState>,
    /// The last beam position reached, if any.
    pub position: Option<PlatePoint>,
}

/// Why one attempt at a command failed without a usable reply.
enum Miss {
    /// Nothing (or only part of a line) within the timeout.
    Timeout,
    /// A line that does not decode.
    Garbled(LdvProtocolError),
    /// A reply that does not answer the command: a late reply to an earlier one.
    Stale(Reply),
}

/// The LDV controller's driver over any [`SerialLine`].
///
/// One command at a time, each waiting for its reply with the specification's timeout ([`Command::timeout_s`],
/// scaled by [`RetryPolicy::timeout_scale`]). After a timeout, a garbled line or a stale reply, the driver assumes
/// more stale bytes may follow: before its next command it resynchronises (sends `SYNC <t>` with a fresh token and
/// discards everything up to its echo), then sends the command again, up to [`RetryPolicy::attempts`] times. Every
/// command of the protocol is idempotent (absolute positions and settings), so sending one twice is harmless.
/// `ERR 7` (busy) is waited out on the driver's [`Clock`]: the only place the driver waits other than reading.
pub struct LdvDriver<T: SerialLine> {
    line: T,
    clock: Arc<dyn Clock>,
    policy: RetryPolicy,
    decoder: ReplyDecoder,
    needs_resync: bool,
    next_token: u32,
    settings: AppliedSettings,
}

impl<T: SerialLine> std::fmt::Debug for LdvDriver<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LdvDriver")
            .field("policy", &self.policy)
            .field("needs_resync", &self.needs_resync)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl<T: SerialLine> LdvDriver<T> {
    /// A driver on an open `line`. It sends nothing yet; its first command is preceded by a resynchronisation,
    /// since the line may hold bytes from an earlier session. `SYNC` tokens count up from 1.
    ///
    /// # Errors
    /// [`VibrometerError::InvalidArgument`] when `policy` is out of range ([`RetryPolicy::validate`]).
    pub fn new(line: T, clock: Arc<dyn Clock>, policy: RetryPolicy) -> Result<Self, VibrometerError> {
        policy.validate()?;
        let settings = AppliedSettings::default();
        Ok(Self { line, clock, policy, decoder: ReplyDecoder::new(), needs_resync: true, next_token: 1, settings })
    }

    /// The settings that [`Vibrometer::reconnect`] re-applies.
    pub fn settings(&self) -> AppliedSettings {
        self.settings
    }

    /// The transport (for example to inspect a mock).
    pub fn line(&self) -> &T {
        &self.line
    }

    /// Sends `command` and returns its proper reply (never `ERR`: that becomes [`VibrometerError::Device`]), with
    /// the retries and resynchronisation described on [`LdvDriver`].
    ///
    /// # Errors
    /// `Device` for an `ERR` reply (`ERR 7` only once the busy retries are spent); `Timeout` when every attempt
    /// failed or resynchronisation failed; `Disconnected` when the line is gone.
    pub fn exchange(&mut self, command: Command) -> Result<Reply, VibrometerError> {
        let mut busy_left = self.policy.busy_retries;
        let mut attempt = 0;
        let mut last_miss = String::new();
        while attempt < self.policy.attempts {
            if self.needs_resync {
                self.resync()?;
            }
            self.send(&command)?;
            let miss = match self.await_reply(&command)? {
                Ok(Reply::Error { code: ErrorCode::Busy, .. }) if busy_left > 0 => {
                    // Busy is not a failed attempt: the controller answered, and asks us to come back.
                    busy_left -= 1;
                    self.clock.sleep_s(self.policy.busy_wait_s);
                    continue;
                }
                Ok(Reply::Error { code, text }) => {
                    return Err(VibrometerError::Device {
                        code: code.number(),
                        message: format!("{}: {text}", code.description()),
                    });
                }
                Ok(reply) => return Ok(reply),
                Err(miss) => miss,
            };
            self.needs_resync = true;
            last_miss = match miss {
                Miss::Timeout => {
                    // A partial line left by a timeout can only be junk now.
                    self.decoder.clear();
                    format!("no reply within {} s", self.timeout_s(&command))
                }
                Miss::Garbled(error) => format!("undecodable reply ({error})"),
                Miss::Stale(reply) => format!("reply {reply:?} does not answer it"),
            };
            attempt += 1;
        }
        Err(VibrometerError::Timeout {
            command: command.to_string(),
            detail: format!("{} attempts, the last: {last_miss}", self.policy.attempts),
        })
    }

    fn timeout_s(&self, command: &Command) -> f64 {
        command.timeout_s() * self.policy.timeout_scale
    }

    fn send(&mut self, command: &Command) -> Result<(), VibrometerError> {
        match self.line.write_all(&encode_command(command)) {
            Ok(()) => Ok(()),
            Err(LineError::Disconnected { reason }) => Err(self.disconnected(reason)),
            Err(LineError::Timeout) => Err(VibrometerError::Timeout {
                command: command.to_string(),
                detail: "the line did not take the bytes".into(),
            }),
        }
    }

    fn disconnected(&mut self, reason: String) -> VibrometerError {
        self.needs_resync = true;
        VibrometerError::Disconnected { reason }
    }

    /// Reads until one line decodes (or fails to), or the command's timeout passes. The outer `Err` is a
    /// disconnect; the inner one a missed reply.
    fn await_reply(&mut self, command: &Command) -> Result<Result<Reply, Miss>, VibrometerError> {
        let timeout_s = self.timeout_s(command);
        let line = self.next_line(timeout_s)?;
        Ok(match line {
            None => Err(Miss::Timeout),
            Some(Err(error)) => Err(Miss::Garbled(error)),
            Some(Ok(reply)) if command.is_answered_by(&reply) => Ok(reply),
            Some(Ok(reply)) => Err(Miss::Stale(reply)),
        })
    }

    /// The next decoded line, or `None` when none completed within `timeout_s` (wall time: the transport's reads
    /// are real-time for a real port and immediate for a mock).
    fn next_line(&mut self, timeout_s: f64) -> Result<Option<Result<Reply, LdvProtocolError>>, VibrometerError> {
        let deadline = Instant::now() + Duration::try_from_secs_f64(timeout_s).unwrap_or(Duration::ZERO);
        let mut buf = [0u8; 256];
        loop {
            if let Some(line) = self.decoder.poll() {
                return Ok(Some(line));
            }
            let remaining_s = deadline.saturating_duration_since(Instant::now()).as_secs_f64();
            if remaining_s <= 0.0 {
                return Ok(None);
            }
            match self.line.read(&mut buf, remaining_s) {
                Ok(n) => self.decoder.push(buf.get(..n).unwrap_or(&buf)),
                Err(LineError::Timeout) => return Ok(None),
                Err(LineError::Disconnected { reason }) => return Err(self.disconnected(reason)),
            }
        }
    }

    /// The specification's resynchronisation: `SYNC <t>` with a fresh token, discarding every reply and decode
    /// error until its echo; a new token after each timeout, up to [`RetryPolicy::resync_attempts`] tokens.
    fn resync(&mut self) -> Result<(), VibrometerError> {
        let timeout_s = REPLY_TIMEOUT_S * self.policy.timeout_scale;
        for _ in 0..self.policy.resync_attempts {
            let token = SyncToken(self.next_token);
            self.next_token = self.next_token.wrapping_add(1);
            let sync = Command::Sync(token);
            self.send(&sync)?;
            // Each discarded line consumes bytes the controller sent; the deadline bounds the loop in time.
            loop {
                match self.next_line(timeout_s)? {
                    Some(Ok(reply)) if sync.is_answered_by(&reply) => {
                        self.needs_resync = false;
                        return Ok(());
                    }
                    Some(_) => continue,
                    None => {
                        self.decoder.clear();
                        break;
                    }
                }
            }
        }
        Err(VibrometerError::Timeout {
            command: "SYNC".into(),
            detail: format!("controller lost: no echo to {} SYNC tokens", self.policy.resync_attempts),
        })
    }

    fn expect_ok(&mut self, command: Command) -> Result<(), VibrometerError> {
        match self.exchange(command)? {
            Reply::Ok => Ok(()),
            other => Err(unexpected(&command, &other)),
        }
    }

    fn apply_range(&mut self, range: VelocityRange) -> Result<(), VibrometerError> {
        self.expect_ok(Command::SetVelocityRange(range))?;
        self.settings.velocity_range = Some(range);
        Ok(())
    }

    fn apply_tracking(&mut self, filter: TrackingFilter) -> Result<(), VibrometerError> {
        self.expect_ok(Command::SetTrackingFilter(filter))?;
        self.settings.tracking = Some(filter);
        Ok(())
    }

    fn apply_laser(&mut self, state: LaserState) -> Result<(), VibrometerError> {
        self.expect_ok(Command::SetLaser(state))?;
        self.settings.laser = Some(state);
        Ok(())
    }

    fn apply_position(&mut self, point: PlatePoint) -> Result<(), VibrometerError> {
        self.expect_ok(Command::MoveTo(point))?;
        self.settings.position = Some(point);
        Ok(())
    }
}

/// A reply that passed [`Command::is_answered_by`] but is not the variant the caller handles: cannot happen with
/// this protocol crate, reported rather than panicking.
fn unexpected(command: &Command, reply: &Reply) -> VibrometerError {
    VibrometerError::Protocol { detail: format!("{command} answered by {reply}") }
}

fn tracking_filter(tracking: Tracking) -> TrackingFilter {
    match tracking {
        Tracking::Off => TrackingFilter::Off,
        Tracking::Slow => TrackingFilter::Slow,
        Tracking::Medium => TrackingFilter::Medium,
        Tracking::Fast => TrackingFilter::Fast,
    }
}

/// The most sensitive range whose full scale reaches `max_velocity_m_s`. Valid range: finite, `0 <` it `<= 10 m/s`.
fn range_for(max_velocity_m_s: f64) -> Result<VelocityRange, VibrometerError> {
    let found = (max_velocity_m_s.is_finite() && max_velocity_m_s > 0.0)
        .then(|| VelocityRange::ALL.into_iter().find(|r| r.full_scale_m_per_s() >= max_velocity_m_s))
        .flatten();
    found.ok_or_else(|| VibrometerError::InvalidArgument {
        detail: format!("max_velocity_m_s = {max_velocity_m_s} is outside (0, 10] m/s"),
    })
}

impl<T: SerialLine> Vibrometer for LdvDriver<T> {
    fn identify(&mut self) -> Result<VibrometerIdentity, VibrometerError> {
        match self.exchange(Command::Identify)? {
            Reply::Identity(id) => Ok(VibrometerIdentity {
                vendor: id.vendor.to_string(),
                model: id.model.to_string(),
                serial: id.serial.to_string(),
                firmware: id.firmware.to_string(),
            }),
            other => Err(unexpected(&Command::Identify, &other)),
        }
    }

    fn move_to(&mut self, x_m: f64, y_m: f64) -> Result<(), VibrometerError> {
        let point = PlatePoint::from_m(x_m, y_m).map_err(|e| VibrometerError::InvalidArgument {
            detail: format!("beam position ({x_m} m, {y_m} m): {e}"),
        })?;
        self.apply_position(point)
    }

    fn signal_level(&mut self) -> Result<f64, VibrometerError> {
        match self.exchange(Command::QuerySignal)? {
            Reply::Signal(level) => Ok(level.fraction()),
            other => Err(unexpected(&Command::QuerySignal, &other)),
        }
    }

    fn set_velocity_range(&mut self, max_velocity_m_s: f64) -> Result<VelocityScale, VibrometerError> {
        let range = range_for(max_velocity_m_s)?;
        self.apply_range(range)?;
        Ok(VelocityScale { m_s_per_v: range.m_per_s_per_v(), full_scale_m_s: range.full_scale_m_per_s() })
    }

    fn set_tracking(&mut self, tracking: Tracking) -> Result<(), VibrometerError> {
        self.apply_tracking(tracking_filter(tracking))
    }

    fn set_laser(&mut self, on: bool) -> Result<(), VibrometerError> {
        self.apply_laser(if on { LaserState::On } else { LaserState::Off })
    }

    /// Reopens the line, resynchronises, and re-applies velocity range, tracking filter, laser and beam position
    /// (in that order, the laser before the move so that the beam lands lit), each only if it was set before.
    fn reconnect(&mut self) -> Result<(), VibrometerError> {
        self.line.reopen().map_err(|e| VibrometerError::Disconnected { reason: e.to_string() })?;
        self.decoder.clear();
        self.needs_resync = true;
        let saved = self.settings;
        if let Some(range) = saved.velocity_range {
            self.apply_range(range)?;
        }
        if let Some(filter) = saved.tracking {
            self.apply_tracking(filter)?;
        }
        if let Some(state) = saved.laser {
            self.apply_laser(state)?;
        }
        if let Some(point) = saved.position {
            self.apply_position(point)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_range_is_the_most_sensitive_that_covers() {
        // Extremes and every boundary: exactly a full scale picks that range; just above picks the next.
        let cases = [
            (1e-9, VelocityRange::MmPerS1),
            (0.01, VelocityRange::MmPerS1),
            (0.010_001, VelocityRange::MmPerS5),
            (0.05, VelocityRange::MmPerS5),
            (0.25, VelocityRange::MmPerS25),
            (1.25, VelocityRange::MmPerS125),
            (1.250_001, VelocityRange::MmPerS1000),
            (10.0, VelocityRange::MmPerS1000),
        ];
        for (v, range) in cases {
            assert_eq!(range_for(v).ok(), Some(range), "{v} m/s");
        }
        for bad in [0.0, -1.0, 10.000_001, f64::NAN, f64::INFINITY] {
            assert!(matches!(range_for(bad), Err(VibrometerError::InvalidArgument { .. })), "{bad} m/s");
        }
    }
}
