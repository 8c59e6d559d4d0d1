//! The host's view of a running stream: packet numbers checked, auto-recovery accounted, codes turned into volts
//! by scan.
//!
//! Rules (User's Guide section 5.2.14 "StreamData" and section 3.2 "Stream Mode"; LabJackPython `streamData`, which
//! counts errorcode-60 packets' TimeStamp as missed scans):
//! - PacketNumber counts packets modulo 256: a jump forward of `d` (`d < 128`) means `d` packets were lost after
//!   the device sent them (`d * SamplesPerPacket / channels` scans); a jump backwards (`d >= 128`) is a stale or
//!   repeated packet and is dropped.
//! - Errorcode 59 (auto-recovery active): the U6's buffer overflowed and it discards new scans while it sends
//!   what it holds; the packet's samples are good.
//! - Errorcode 60 (auto-recovery report): the packet starts with one dummy scan (every sample `0xFFFF`) and its
//!   TimeStamp is the number of scans discarded, the dummy included: the first real scan after it is TimeStamp
//!   scans after the last one before the overflow.
//! - Any other nonzero errorcode ends the stream (55 `STREAM_SCAN_OVERLAP`, 63 `STREAM_AUTORECOVER_OVERFLOW`...).
//!
//! This assembler needs every packet to hold whole scans (SamplesPerPacket a multiple of the channel count), so
//! that a packet lost costs whole scans and the dummy scan is the packet's first.

use crate::calibration::{Calibration, is_rail};
use crate::config::{Gain, StreamConfig};
use crate::error::U6Error;
use crate::errorcode::Errorcode;
use crate::stream::StreamPacket;

/// Something the stream reported or lost, before a packet's scans.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamEvent {
    /// Packets lost in transit (a PacketNumber gap).
    PacketsMissed {
        /// Packets lost.
        packets: u32,
        /// Scans they held.
        scans: u64,
    },
    /// A packet whose number lies behind the expected one: dropped.
    Stale {
        /// Its PacketNumber.
        packet_number: u8,
    },
    /// The device's buffer had overflowed (errorcode 59): scans are being discarded at the source.
    AutoRecoverActive,
    /// The auto-recovery report (errorcode 60): this many scans were discarded (the dummy scan included).
    ScansDiscarded {
        /// Scans discarded.
        scans: u64,
    },
}

/// What one packet gave.
#[derive(Debug, Clone, PartialEq)]
pub struct PacketScans {
    /// What happened before this packet's scans.
    pub events: Vec<StreamEvent>,
    /// Scan index of the first scan below (scans since the stream started, lost ones counted).
    pub first_scan_index: u64,
    /// Volts per channel in scan-list order, each `scans` long (0 for a dropped packet).
    pub volts: Vec<Vec<f64>>,
    /// Some sample sat on a rail.
    pub clipped: bool,
}

/// Counters of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamStats {
    /// Packets accepted.
    pub packets: u64,
    /// Packets lost in transit.
    pub packets_missed: u64,
    /// Scans discarded by the device's auto-recovery.
    pub scans_discarded: u64,
    /// Packets flagged with errorcode 59.
    pub autorecover_packets: u64,
    /// Stale packets dropped.
    pub stale_packets: u64,
    /// The highest Backlog seen (0-255; 256 would be a full buffer).
    pub max_backlog: u8,
}

/// Tracks one stream (see the module documentation).
#[derive(Debug, Clone)]
pub struct ScanAssembler {
    gains: Vec<Gain>,
    calibration: Calibration,
    samples_per_packet: usize,
    next_packet: u8,
    next_scan: u64,
    stats: StreamStats,
}

impl ScanAssembler {
    /// A tracker for a stream configured by `config`, converting with `calibration`.
    ///
    /// # Errors
    /// [`U6Error::InvalidField`] when SamplesPerPacket is not a positive multiple of the channel count.
    pub fn new(config: &StreamConfig, calibration: Calibration) -> Result<Self, U6Error> {
        let n = config.channels.len();
        let spp = usize::from(config.samples_per_packet);
        if n == 0 || spp == 0 || spp % n != 0 {
            return Err(U6Error::InvalidField {
                what: "StreamConfig",
                field: "SamplesPerPacket",
                value: spp as u64,
                reason: "this host reads packets of whole scans: a positive multiple of the channel count",
            });
        }
        Ok(Self {
            gains: config.channels.iter().map(|c| c.gain).collect(),
            calibration,
            samples_per_packet: spp,
            next_packet: 0,
            next_scan: 0,
            stats: StreamStats::default(),
        })
    }

    /// Counters so far.
    pub fn stats(&self) -> &StreamStats {
        &self.stats
    }

    /// The scan index the next scan will have.
    pub fn next_scan_index(&self) -> u64 {
        self.next_scan
    }

    /// Takes the next packet received.
    ///
    /// # Errors
    /// [`U6Error::StreamError`] for an errorcode that ends the stream; [`U6Error::InvalidField`] for a packet
    /// of another length than configured.
    pub fn accept(&mut self, packet: &StreamPacket) -> Result<PacketScans, U6Error> {
        let n = self.gains.len();
        let mut events = Vec::new();
        let gap = packet.packet_number.wrapping_sub(self.next_packet);
        if gap >= 128 {
            self.stats.stale_packets += 1;
            events.push(StreamEvent::Stale { packet_number: packet.packet_number });
            return Ok(PacketScans {
                events,
                first_scan_index: self.next_scan,
                volts: vec![Vec::new(); n],
                clipped: false,
            });
        }
        if packet.samples.len() != self.samples_per_packet {
            return Err(U6Error::InvalidField {
                what: "StreamData",
                field: "samples",
                value: packet.samples.len() as u64,
                reason: "differs from the configured SamplesPerPacket",
            });
        }
        if gap > 0 {
            let scans = u64::from(gap) * (self.samples_per_packet / n) as u64;
            self.stats.packets_missed += u64::from(gap);
            self.next_scan += scans;
            events.push(StreamEvent::PacketsMissed { packets: u32::from(gap), scans });
        }
        self.next_packet = packet.packet_number.wrapping_add(1);
        self.stats.packets += 1;
        self.stats.max_backlog = self.stats.max_backlog.max(packet.backlog);
        let mut samples = packet.samples.as_slice();
        match packet.errorcode {
            Errorcode::OK => {}
            Errorcode::STREAM_AUTORECOVER_ACTIVE => {
                self.stats.autorecover_packets += 1;
                events.push(StreamEvent::AutoRecoverActive);
            }
            Errorcode::STREAM_AUTORECOVER_REPORT => {
                let scans = u64::from(packet.timestamp.max(1));
                self.stats.scans_discarded += scans;
                self.next_scan += scans;
                events.push(StreamEvent::ScansDiscarded { scans });
                samples = &samples[n..];
            }
            errorcode => return Err(U6Error::StreamError { packet_number: packet.packet_number, errorcode }),
        }
        let first_scan_index = self.next_scan;
        let scans = samples.len() / n;
        let mut volts = vec![Vec::with_capacity(scans); n];
        let mut clipped = false;
        for scan in samples.chunks_exact(n) {
            for ((out, &gain), &code) in volts.iter_mut().zip(&self.gains).zip(scan) {
                clipped |= is_rail(code);
                out.push(self.calibration.volts(gain, code));
            }
        }
        self.next_scan += scans as u64;
        Ok(PacketScans { events, first_scan_index, volts, clipped })
    }
}
