//! Fault injection: a schedule of faults keyed by IN-transfer number, written by hand or drawn from a seed.

use metaplate_core::rng::SplitMix64;

/// A fault the mock transport injects when the host attempts a given IN transfer (on either IN endpoint).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// The IN endpoints stall: this read and the `reads - 1` after it time out. The device's responses and
    /// stream data are held, not lost, and arrive once the stall ends.
    Stall {
        /// Reads that time out (at least 1 to have an effect).
        reads: u32,
    },
    /// The device drops off the bus (it power-cycles: configuration and acquisition are lost). Every transfer
    /// fails with `Disconnected` until the host reopens it.
    Disconnect,
    /// The U6's stream buffer overflows: auto-recovery discards `scans` scans (and what the buffer held), the
    /// next packet carries errorcode 59 and the one after errorcode 60 with the count. Nothing happens while idle.
    Overrun {
        /// Scans discarded beyond the buffer's contents.
        scans: u32,
    },
    /// An overflow auto-recovery cannot count: the next packet carries errorcode 63 and the stream ends.
    FatalOverrun,
    /// The first StreamData packet of this read is lost in transit (the host sees a PacketNumber gap).
    DropPacket,
}

/// Stream of [`FaultSchedule::seeded`]'s draws ("faults" in ASCII).
const FAULT_STREAM: u64 = 0x6661_756c_7473;

/// Probabilities per IN transfer for [`FaultSchedule::seeded`].
///
/// Valid range: each in `0..=1` (values outside are clamped, NaN counts as 0); their sum at most 1 (beyond,
/// the later kinds are drawn less often than asked).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaultRates {
    /// Probability that a read starts a stall of 1 to `max_stall_reads` reads.
    pub stall: f64,
    /// The longest stall drawn, reads (at least 1).
    pub max_stall_reads: u32,
    /// Probability of a disconnect.
    pub disconnect: f64,
    /// Probability of a recoverable overrun of 1 to 100 scans.
    pub overrun: f64,
    /// Probability that a stream read loses its first packet in transit.
    pub drop_packet: f64,
}

/// Faults by IN-transfer number (0 for the host's first read attempt), in order.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FaultSchedule {
    events: Vec<(u64, Fault)>,
}

fn probability(p: f64) -> f64 {
    if p.is_nan() { 0.0 } else { p.clamp(0.0, 1.0) }
}

impl FaultSchedule {
    /// No faults.
    pub fn none() -> Self {
        Self::default()
    }

    /// Adds `fault` at IN transfer `read_index` (several faults at one index apply in the order added).
    pub fn at(mut self, read_index: u64, fault: Fault) -> Self {
        let pos = self.events.partition_point(|&(i, _)| i <= read_index);
        self.events.insert(pos, (read_index, fault));
        self
    }

    /// Draws faults for IN transfers `0..horizon_reads` from `rates`, deterministically from `seed` (the same
    /// seed and rates always give the same schedule).
    pub fn seeded(seed: u64, rates: FaultRates, horizon_reads: u64) -> Self {
        // The suite's one seeded generator; the stream constant keeps fault draws apart from other draws of `seed`.
        let mut rng = SplitMix64::new(seed, FAULT_STREAM);
        let stall = probability(rates.stall);
        let disconnect = probability(rates.disconnect);
        let overrun = probability(rates.overrun);
        let drop_packet = probability(rates.drop_packet);
        let mut events = Vec::new();
        for read_index in 0..horizon_reads {
            let u = rng.uniform();
            let fault = if u < stall {
                Fault::Stall { reads: rng.in_range(1, u64::from(rates.max_stall_reads.max(1))) as u32 }
            } else if u < stall + disconnect {
                Fault::Disconnect
            } else if u < stall + disconnect + overrun {
                Fault::Overrun { scans: rng.in_range(1, 100) as u32 }
            } else if u < stall + disconnect + overrun + drop_packet {
                Fault::DropPacket
            } else {
                continue;
            };
            events.push((read_index, fault));
        }
        Self { events }
    }

    /// The scheduled faults, by IN-transfer number, in order.
    pub fn events(&self) -> &[(u64, Fault)] {
        &self.events
    }

    /// The faults due at `read_index`.
    pub(crate) fn due(&self, read_index: u64) -> impl Iterator<Item = Fault> + '_ {
        let start = self.events.partition_point(|&(i, _)| i < read_index);
        self.events[start..].iter().take_while(move |&&(i, _)| i == read_index).map(|&(_, f)| f)
    }
}
