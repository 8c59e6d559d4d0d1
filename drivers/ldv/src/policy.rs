//! How hard the driver tries before it gives up: attempts and reply timeouts.

use metaplate_core::vibrometer::VibrometerError;

/// The driver's retry bounds. Every loop in the driver is bounded by these numbers and by the reply timeout, so no
/// call can hang: the worst case of one request is `attempts` reply timeouts (a verified setting: twice that, its
/// `Set` and its read-back).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetryPolicy {
    /// Times a request is sent before the call fails with `Timeout` (no reply, a garbled or unusable reply, a
    /// setting that did not read back). Valid range: 1 to 100.
    pub attempts: u32,
    /// How long to wait for a reply line, s, before sending again. Valid range: finite, 0.001 to 60 s.
    pub reply_timeout_s: f64,
    /// Factor applied to the reply timeout: 1 in the lab; smaller in tests against a fast mock, so that timeouts
    /// cost little wall time. Valid range: finite, 0.001 to 100.
    pub timeout_scale: f64,
}

impl Default for RetryPolicy {
    /// 3 attempts; 0.25 s per reply (a `Get` is answered within milliseconds at 115200 baud; the margin covers a
    /// controller busy with its front panel); unscaled.
    fn default() -> Self {
        Self { attempts: 3, reply_timeout_s: 0.25, timeout_scale: 1.0 }
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
        if !(0.001..=60.0).contains(&self.reply_timeout_s) {
            return bad(format!("reply_timeout_s = {} is outside 0.001..=60 s", self.reply_timeout_s));
        }
        if !(0.001..=100.0).contains(&self.timeout_scale) {
            return bad(format!("timeout_scale = {} is outside 0.001..=100", self.timeout_scale));
        }
        Ok(())
    }

    /// The reply timeout in force, s.
    pub fn scaled_timeout_s(&self) -> f64 {
        self.reply_timeout_s * self.timeout_scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_extremes_are_checked() {
        let base = RetryPolicy::default();
        assert!(base.validate().is_ok());
        for policy in [
            RetryPolicy { attempts: 1, reply_timeout_s: 0.001, timeout_scale: 0.001 },
            RetryPolicy { attempts: 100, reply_timeout_s: 60.0, timeout_scale: 100.0 },
        ] {
            assert!(policy.validate().is_ok(), "{policy:?}");
        }
        for policy in [
            RetryPolicy { attempts: 0, ..base },
            RetryPolicy { attempts: 101, ..base },
            RetryPolicy { reply_timeout_s: f64::NAN, ..base },
            RetryPolicy { reply_timeout_s: 0.0, ..base },
            RetryPolicy { timeout_scale: 0.0, ..base },
            RetryPolicy { timeout_scale: f64::INFINITY, ..base },
        ] {
            assert!(matches!(policy.validate(), Err(VibrometerError::InvalidArgument { .. })), "{policy:?}");
        }
    }
}
