//! How hard the driver tries before it gives up: retries, resynchronisation, busy waits, timeouts.

use metaplate_core::vibrometer::VibrometerError;

/// The driver's retry bounds. Every loop in the driver is bounded by these numbers and by the reply timeouts, so no
/// call can hang: the worst case of one call is `attempts x (resync_attempts + 1)` reply timeouts plus
/// `busy_retries x busy_wait_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetryPolicy {
    /// Times a command is sent before the call fails with `Timeout` (no reply, garbled or stale replies). Valid
    /// range: 1 to 100.
    pub attempts: u32,
    /// `SYNC` tokens tried in one resynchronisation before the controller is reported lost (the specification
    /// says 3). Valid range: 1 to 100.
    pub resync_attempts: u32,
    /// Times an `ERR 7` (busy) reply is waited out before it is reported as a `Device` error. Valid range: 0 to
    /// 1000.
    pub busy_retries: u32,
    /// Wait after an `ERR 7` before sending again, s, on the driver's clock (the specification says 100 ms). Valid
    /// range: finite, 0 to 10 s.
    pub busy_wait_s: f64,
    /// Factor applied to every reply timeout of the specification (`Command::timeout_s`): 1 in the lab; smaller in
    /// tests against a fast mock, so that timeouts cost little wall time. Valid range: finite, 0.001 to 100.
    pub timeout_scale: f64,
}

impl Default for RetryPolicy {
    /// The specification's values: 3 attempts, 3 `SYNC` tokens, busy waits of 100 ms up to 10 times (1 s, longer
    /// than a front-panel touch), unscaled timeouts.
    fn default() -> Self {
        Self { attempts: 3, resync_attempts: 3, busy_retries: 10, busy_wait_s: 0.1, timeout_scale: 1.0 }
    }
}

impl RetryPolicy {
    /// Checks every field against its valid range.
    ///
    /// # Errors
    /// [`VibrometerError::InvalidArgument`] naming the first field out of range.
    pub fn validate(&self) -> Result<(), VibrometerError> {
        let bad = |detail: String| Err(VibrometerError::InvalidArgument { detail });
        if !(1..=100).contains(&self.attempts) {
            return bad(format!("attempts = {} is outside 1..=100", self.attempts));
        }
        if !(1..=100).contains(&self.resync_attempts) {
            return bad(format!("resync_attempts = {} is outside 1..=100", self.resync_attempts));
        }
        if self.busy_retries > 1000 {
            return bad(format!("busy_retries = {} is outside 0..=1000", self.busy_retries));
        }
        if !(0.0..=10.0).contains(&self.busy_wait_s) {
            return bad(format!("busy_wait_s = {} is outside 0..=10 s", self.busy_wait_s));
        }
        if !(0.001..=100.0).contains(&self.timeout_scale) {
            return bad(format!("timeout_scale = {} is outside 0.001..=100", self.timeout_scale));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_extremes_are_checked() {
        assert!(RetryPolicy::default().validate().is_ok());
        let base = RetryPolicy::default();
        let edges_ok = [
            RetryPolicy { attempts: 1, resync_attempts: 1, busy_retries: 0, busy_wait_s: 0.0, timeout_scale: 0.001 },
            RetryPolicy {
                attempts: 100,
                resync_attempts: 100,
                busy_retries: 1000,
                busy_wait_s: 10.0,
                timeout_scale: 100.0,
            },
        ];
        for policy in edges_ok {
            assert!(policy.validate().is_ok(), "{policy:?}");
        }
        let bad = [
            RetryPolicy { attempts: 0, ..base },
            RetryPolicy { attempts: 101, ..base },
            RetryPolicy { resync_attempts: 0, ..base },
            RetryPolicy { busy_retries: 1001, ..base },
            RetryPolicy { busy_wait_s: f64::NAN, ..base },
            RetryPolicy { busy_wait_s: -0.1, ..base },
            RetryPolicy { timeout_scale: 0.0, ..base },
            RetryPolicy { timeout_scale: f64::INFINITY, ..base },
        ];
        for policy in bad {
            assert!(matches!(policy.validate(), Err(VibrometerError::InvalidArgument { .. })), "{policy:?}");
        }
    }
}
