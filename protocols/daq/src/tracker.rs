//! Host-side stream bookkeeping: lost, duplicated and late packets, sample-clock jumps, overruns and clipping.
//!
//! Create one [`StreamTracker`] per acquisition (when `Start` is acknowledged), pass it every decoded
//! [`SamplePacket`] in arrival order, append the samples of packets it marks `fresh`, and at the end ask
//! [`StreamStats::is_contiguous`]: a recording that is not contiguous has lost samples and must be repeated or
//! repaired. For example:
//!
//! ```
//! use metaplate_daq_protocol::{ChannelConfig, Configure, SampleFlags, SamplePacket, StreamTracker};
//!
//! let config = Configure {
//!     sample_rate_hz: 24_000,
//!     samples_per_packet: 2,
//!     channels: vec![ChannelConfig { index: 0, range_mv: 10_000 }],
//! };
//! let mut tracker = StreamTracker::new(&config)?;
//! let packet = |packet_seq, first_sample_index, overrun| SamplePacket {
//!     packet_seq,
//!     first_sample_index,
//!     flags: SampleFlags { overrun, clipped: false },
//!     n_channels: 1,
//!     samples: vec![100, -100],
//! };
//! assert!(tracker.track(&packet(0, 0, false)).fresh);
//! // The device lost 6 samples to an overrun before packet 1.
//! let outcome = tracker.track(&packet(1, 8, true));
//! assert!(outcome.fresh && !outcome.events.is_empty());
//! assert!(!tracker.stats().is_contiguous());
//! assert_eq!(tracker.stats().samples_missing, 6);
//! # Ok::<(), metaplate_daq_protocol::DaqError>(())
//! ```

use crate::codes::ErrorCode;
use crate::command::{ChannelConfig, Configure};
use crate::error::DaqError;
use crate::reply::SamplePacket;
use crate::scale::{is_rail, raw_to_volts};

/// How far back (in packets) a duplicate is recognised; an older repeat is reported as [`StreamEvent::OutOfOrder`].
pub const DUPLICATE_WINDOW: u32 = 64;

/// Something the tracker noticed about one packet.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StreamEvent {
    /// `count` packets, from `first_missing_seq` on, never arrived before this one (lost between device and host).
    PacketsLost {
        /// The first missing `packet_seq`.
        first_missing_seq: u32,
        /// How many are missing.
        count: u32,
    },
    /// The device flagged this packet: it lost samples (its buffer overflowed) before this packet.
    Overrun {
        /// The flagged packet.
        packet_seq: u32,
    },
    /// This packet's first sample index is not where the previous fresh packet ended. Forward
    /// (`got_index > expected_index`): `got_index - expected_index` samples per channel are missing, explained by
    /// lost packets or an overrun reported for the same packet, or by nothing (a device fault). Backward: the
    /// device's clock went back (a device fault).
    Discontinuity {
        /// The packet.
        packet_seq: u32,
        /// The sample index the previous fresh packet implies.
        expected_index: u64,
        /// The packet's `first_sample_index`.
        got_index: u64,
    },
    /// A packet whose `packet_seq` was already seen within the last [`DUPLICATE_WINDOW`] packets; dropped.
    Duplicate {
        /// The repeated packet.
        packet_seq: u32,
    },
    /// A packet older than the newest one seen and not seen before (or too old to tell): it arrived after its
    /// place in the stream had passed (it was counted lost); dropped.
    OutOfOrder {
        /// The late packet.
        packet_seq: u32,
        /// The `packet_seq` the tracker expected.
        expected_seq: u32,
    },
    /// A sample sits on a rail, or the device flagged clipping: the input exceeded the configured range.
    Clipped {
        /// The packet.
        packet_seq: u32,
    },
    /// The packet's channel count differs from the configuration, or it holds more samples than
    /// `samples_per_packet`; dropped (its samples count as lost).
    WrongShape {
        /// The packet.
        packet_seq: u32,
        /// Its channel count.
        n_channels: usize,
        /// Its samples per channel.
        n_samples: usize,
    },
}

impl StreamEvent {
    /// Whether the event means samples are missing from the recording (lost or late packets, overrun, a sample
    /// clock jump, an unusable packet). Duplicates and clipping lose nothing.
    pub fn is_loss(&self) -> bool {
        !matches!(self, StreamEvent::Duplicate { .. } | StreamEvent::Clipped { .. })
    }
}

/// What the tracker concluded about one packet.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Tracked {
    /// Whether this packet continues the stream and its samples should be appended to the recording. `false` for
    /// duplicates, late packets and packets of the wrong shape.
    pub fresh: bool,
    /// What was noticed, in the order: lost packets, overrun, discontinuity, clipping (or one of duplicate, out of
    /// order, wrong shape). Empty for a clean packet.
    pub events: Vec<StreamEvent>,
}

/// Running totals over an acquisition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamStats {
    /// Fresh packets (appended).
    pub packets: u64,
    /// Samples per channel in fresh packets.
    pub samples: u64,
    /// Packets that never arrived in their place (including those reported by [`StreamTracker::finish`]).
    pub packets_lost: u64,
    /// Packets flagged with an overrun.
    pub overruns: u64,
    /// Sample-index discontinuities, forward or backward.
    pub discontinuities: u64,
    /// Samples per channel missing, from forward sample-index jumps.
    pub samples_missing: u64,
    /// Duplicated packets dropped.
    pub duplicates: u64,
    /// Late packets dropped.
    pub out_of_order: u64,
    /// Packets with clipped samples.
    pub clipped_packets: u64,
    /// Packets of the wrong shape dropped.
    pub wrong_shape: u64,
}

impl StreamStats {
    /// Whether every sample from index 0 to `samples` arrived exactly once and in order: no lost, late or unusable
    /// packet, no overrun, no discontinuity. Duplicates (dropped) and clipping do not break contiguity.
    pub fn is_contiguous(&self) -> bool {
        self.packets_lost == 0
            && self.overruns == 0
            && self.discontinuities == 0
            && self.out_of_order == 0
            && self.wrong_shape == 0
    }

    /// Contiguous, and nothing else happened either: no duplicate and no clipped sample.
    pub fn is_clean(&self) -> bool {
        self.is_contiguous() && self.duplicates == 0 && self.clipped_packets == 0
    }
}

/// Checks a packet stream of one acquisition against its configuration; see the [module documentation](self).
#[derive(Debug, Clone)]
pub struct StreamTracker {
    channels: Vec<ChannelConfig>,
    samples_per_packet: usize,
    /// The `packet_seq` expected next (one past the newest fresh packet).
    next_seq: u32,
    /// Bit `i` set: packet `next_seq - 1 - i` arrived.
    seen: u64,
    /// The sample index expected next (where the newest fresh packet ended).
    next_index: u64,
    stats: StreamStats,
}

impl StreamTracker {
    /// A tracker for a new acquisition with `config`: it expects packet 0 starting at sample index 0.
    ///
    /// # Errors
    /// [`DaqError::ConfigRejected`] ([`ErrorCode::BadConfig`]) if `config` has no channels, a range of 0 mV or a
    /// packet size of 0 (such a configuration cannot produce a stream).
    pub fn new(config: &Configure) -> Result<Self, DaqError> {
        let bad = |reason: &str| DaqError::ConfigRejected { code: ErrorCode::BadConfig, reason: reason.into() };
        if config.channels.is_empty() {
            return Err(bad("no channels"));
        }
        if config.channels.iter().any(|c| c.range_mv == 0) {
            return Err(bad("a channel has a range of 0 mV"));
        }
        if config.samples_per_packet == 0 {
            return Err(bad("samples_per_packet is 0"));
        }
        Ok(Self {
            channels: config.channels.clone(),
            samples_per_packet: usize::from(config.samples_per_packet),
            next_seq: 0,
            seen: 0,
            next_index: 0,
            stats: StreamStats::default(),
        })
    }

    /// The totals so far.
    pub fn stats(&self) -> &StreamStats {
        &self.stats
    }

    /// Takes the next packet in arrival order and says whether to append it, and what was noticed.
    pub fn track(&mut self, packet: &SamplePacket) -> Tracked {
        let seq = packet.packet_seq;
        if let Err(DaqError::PacketShape { n_channels, n_samples, .. }) = self.check_shape(packet) {
            self.stats.wrong_shape += 1;
            return Tracked {
                fresh: false,
                events: vec![StreamEvent::WrongShape { packet_seq: seq, n_channels, n_samples }],
            };
        }
        let ahead = seq.wrapping_sub(self.next_seq);
        // Serial-number arithmetic (RFC 1982): up to half the sequence space ahead is new, the rest is behind.
        if ahead >= 1 << 31 {
            return self.behind(seq);
        }
        let mut events = Vec::new();
        if ahead > 0 {
            events.push(StreamEvent::PacketsLost { first_missing_seq: self.next_seq, count: ahead });
            self.stats.packets_lost += u64::from(ahead);
        }
        self.seen = if ahead >= 64 { 0 } else { self.seen << ahead };
        self.seen = (self.seen << 1) | 1;
        self.next_seq = seq.wrapping_add(1);
        if packet.flags.overrun {
            events.push(StreamEvent::Overrun { packet_seq: seq });
            self.stats.overruns += 1;
        }
        let got_index = packet.first_sample_index;
        if got_index != self.next_index {
            events.push(StreamEvent::Discontinuity { packet_seq: seq, expected_index: self.next_index, got_index });
            self.stats.discontinuities += 1;
            self.stats.samples_missing =
                self.stats.samples_missing.saturating_add(got_index.saturating_sub(self.next_index));
        }
        let n_samples = packet.n_samples() as u64;
        self.next_index = got_index.saturating_add(n_samples);
        if packet.flags.clipped || packet.samples.iter().any(|&s| is_rail(s)) {
            events.push(StreamEvent::Clipped { packet_seq: seq });
            self.stats.clipped_packets += 1;
        }
        self.stats.packets += 1;
        self.stats.samples = self.stats.samples.saturating_add(n_samples);
        Tracked { fresh: true, events }
    }

    /// A packet behind `next_seq`: a duplicate if the window remembers it, late otherwise.
    fn behind(&mut self, seq: u32) -> Tracked {
        let back = self.next_seq.wrapping_sub(seq); // >= 1
        let bit = 1u64.checked_shl(back - 1).filter(|_| back <= DUPLICATE_WINDOW);
        let event = match bit {
            Some(bit) if self.seen & bit != 0 => {
                self.stats.duplicates += 1;
                StreamEvent::Duplicate { packet_seq: seq }
            }
            _ => {
                if let Some(bit) = bit {
                    // Remember it, so a second copy of the late packet reads as a duplicate.
                    self.seen |= bit;
                }
                self.stats.out_of_order += 1;
                StreamEvent::OutOfOrder { packet_seq: seq, expected_seq: self.next_seq }
            }
        };
        Tracked { fresh: false, events: vec![event] }
    }

    /// Ends the acquisition with the `next_packet_seq` of the device's `Stopped` message: reports packets lost at
    /// the end of the stream (which no later packet revealed), or `None`.
    pub fn finish(&mut self, next_packet_seq: u32) -> Option<StreamEvent> {
        let ahead = next_packet_seq.wrapping_sub(self.next_seq);
        if ahead == 0 || ahead >= 1 << 31 {
            return None;
        }
        self.stats.packets_lost += u64::from(ahead);
        let event = StreamEvent::PacketsLost { first_missing_seq: self.next_seq, count: ahead };
        self.next_seq = next_packet_seq;
        Some(event)
    }

    fn check_shape(&self, packet: &SamplePacket) -> Result<(), DaqError> {
        let n_channels = usize::from(packet.n_channels);
        let n_samples = packet.n_samples();
        let whole = n_channels > 0 && packet.samples.len() == n_channels * n_samples;
        if whole && n_channels == self.channels.len() && (1..=self.samples_per_packet).contains(&n_samples) {
            return Ok(());
        }
        Err(DaqError::PacketShape {
            packet_seq: packet.packet_seq,
            n_channels,
            n_samples,
            expected_channels: self.channels.len(),
            max_samples: self.samples_per_packet,
        })
    }

    /// The packet's samples in volts, one vector per channel in configuration order, using each channel's
    /// configured range (see [`crate::scale`]).
    ///
    /// # Errors
    /// [`DaqError::PacketShape`] if the packet does not match the configuration.
    pub fn volts(&self, packet: &SamplePacket) -> Result<Vec<Vec<f64>>, DaqError> {
        self.check_shape(packet)?;
        let n = self.channels.len();
        Ok(self
            .channels
            .iter()
            .enumerate()
            .map(|(pos, ch)| {
                packet.samples.iter().skip(pos).step_by(n).map(|&s| raw_to_volts(s, ch.range_mv)).collect()
            })
            .collect())
    }
}
