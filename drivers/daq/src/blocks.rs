//! Blocks of scans cut from StreamData packets: each block contiguous in the device's scan clock, what was lost
//! before it in its integrity.

use metaplate_core::daq::{BlockIntegrity, DaqBlock};
use metaplate_u6_protocol::{PacketScans, StreamEvent};

/// The block being filled.
#[derive(Debug, Default)]
pub(crate) struct BlockBuilder {
    /// Scans per channel of a full block.
    block_len: usize,
    /// Scan index of the first scan held.
    first: u64,
    /// Volts per channel.
    volts: Vec<Vec<f64>>,
    /// What was lost before the first scan held, and whether a held packet clipped.
    integrity: BlockIntegrity,
    /// Losses seen with no scan held yet: charged to the next scans.
    pending: BlockIntegrity,
    /// Whether the last packet taken clipped.
    last_packet_clipped: bool,
}

impl BlockBuilder {
    pub fn new(block_len: usize, channels: usize) -> Self {
        Self { block_len: block_len.max(1), volts: vec![Vec::new(); channels], ..Self::default() }
    }

    fn held(&self) -> usize {
        self.volts.first().map_or(0, Vec::len)
    }

    /// A full block, if enough scans are held.
    pub fn ready(&mut self) -> Option<DaqBlock> {
        (self.held() >= self.block_len).then(|| self.split())
    }

    /// Takes one packet's scans; returns the block being filled when the packet's losses end it (the packet's
    /// scans then start the next). Full blocks are taken with [`ready`](Self::ready).
    pub fn push(&mut self, scans: PacketScans) -> Option<DaqBlock> {
        let mut gap = BlockIntegrity::default();
        for event in &scans.events {
            match *event {
                StreamEvent::PacketsMissed { packets, scans } => {
                    gap.packets_lost += u64::from(packets);
                    gap.samples_missing += scans;
                }
                StreamEvent::ScansDiscarded { scans } => {
                    gap.samples_missing += scans;
                    gap.overrun = true;
                }
                // The packet's scans continue the stream: the gap comes with the report (errorcode 60).
                StreamEvent::AutoRecoverActive | StreamEvent::Stale { .. } => {}
            }
        }
        let finished = if gap.is_contiguous() { None } else { self.take() };
        let (packets_lost, samples_missing) = (gap.packets_lost, gap.samples_missing);
        self.pending.packets_lost += packets_lost;
        self.pending.samples_missing += samples_missing;
        self.pending.overrun |= gap.overrun;
        let count = scans.volts.first().map_or(0, Vec::len);
        if count == 0 {
            return finished;
        }
        if self.held() == 0 {
            self.first = scans.first_scan_index;
            self.integrity = std::mem::take(&mut self.pending);
        }
        self.integrity.clipped |= scans.clipped;
        self.last_packet_clipped = scans.clipped;
        for (out, v) in self.volts.iter_mut().zip(scans.volts) {
            out.extend(v);
        }
        finished
    }

    /// The scans held as a block (if any), leaving nothing held.
    fn take(&mut self) -> Option<DaqBlock> {
        if self.held() == 0 {
            return None;
        }
        let volts = self.volts.iter_mut().map(std::mem::take).collect();
        Some(DaqBlock { first_sample_index: self.first, volts, integrity: std::mem::take(&mut self.integrity) })
    }

    /// The first `block_len` scans as a block; the rest stay held, contiguous with it. A packet that straddles the
    /// cut marks both halves clipped if it clipped (its codes are not tracked scan by scan).
    fn split(&mut self) -> DaqBlock {
        let n = self.block_len;
        let volts: Vec<Vec<f64>> = self.volts.iter_mut().map(|v| v.drain(..n).collect()).collect();
        let block = DaqBlock { first_sample_index: self.first, volts, integrity: std::mem::take(&mut self.integrity) };
        self.first += n as u64;
        self.integrity.clipped = self.held() > 0 && self.last_packet_clipped;
        block
    }
}
