//! A tiny deterministic random source (SplitMix64), so that a scene and its seed give bit-identical draws on every
//! platform and with every dependency version. The mock devices use it too, as a counter-based generator
//! ([`mix64`] of a key).

/// SplitMix64's increment (the golden ratio in 64 bits).
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function applied to `z + GOLDEN_GAMMA`: a well-mixed 64-bit hash of `z`. As a generator,
/// `mix64(key)` gives independent-looking draws for distinct keys without any state.
pub fn mix64(z: u64) -> u64 {
    let mut z = z.wrapping_add(GOLDEN_GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in (0, 1) from the top 53 bits of `bits`: never exactly 0, so its logarithm is finite.
pub fn unit_open(bits: u64) -> f64 {
    ((bits >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

/// SplitMix64 (Steele, Lea & Flood 2014): a 64-bit state, one multiply-xorshift output per step.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A stream for `seed`, separated from other streams of the same seed by `stream` (any constant).
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut s = Self(seed ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        s.next_u64();
        s
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let out = mix64(self.0);
        self.0 = self.0.wrapping_add(GOLDEN_GAMMA);
        out
    }

    /// Uniform in (0, 1): 53 random bits, never exactly 0.
    pub fn uniform(&mut self) -> f64 {
        unit_open(self.next_u64())
    }

    /// Uniform in `lo..=hi` (`lo` when `hi <= lo`), without bias: Lemire's multiply-shift with rejection.
    pub fn in_range(&mut self, lo: u64, hi: u64) -> u64 {
        let Some(span) = hi.checked_sub(lo).filter(|&d| d > 0).and_then(|d| d.checked_add(1)) else {
            // hi <= lo, or the full 64-bit range (span 2^64).
            return if hi <= lo { lo } else { self.next_u64() };
        };
        // Reject the low products that would make the first `2^64 mod span` values more likely.
        let threshold = span.wrapping_neg() % span;
        loop {
            let m = u128::from(self.next_u64()) * u128::from(span);
            if (m as u64) >= threshold {
                return lo + (m >> 64) as u64;
            }
        }
    }

    /// Standard normal (Box-Muller; one of the pair is discarded to keep the stream simple).
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}
