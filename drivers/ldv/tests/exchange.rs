//! Byte-exact exchanges: each `Vibrometer` call against a script of (line the driver must write, bytes the
//! controller answers). A write that differs from the script fails the test at once. Where each exchange comes
//! from is noted beside it: *PLACE* is github.com/PALab/place, `place/plugins/polytec/polytec.py`; *PLACE (old)*
//! its `place/automate/polytec/vibrometer.py` before commit 42a86fb; *mock* marks this project's reading of an
//! attribute the public sources do not show.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![allow(clippy::unwrap_used)]

use std::collections::VecDeque;

use metaplate_core::vibrometer::{Tracking, Vibrometer, VibrometerError};
use metaplate_ldv::{DecoderChoice, LineError, PolytecConfig, PolytecDriver, RetryPolicy, SerialLine};

/// A line that plays a script: every write must equal the next expected line, which queues its reply.
struct ScriptedLine {
    script: VecDeque<(&'static str, &'static str)>,
    pending: Vec<u8>,
}

impl SerialLine for ScriptedLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        let written = String::from_utf8_lossy(bytes).into_owned();
        let (expected, reply) = self.script.pop_front().unwrap_or_else(|| panic!("unscripted write {written:?}"));
        assert_eq!(written, format!("{expected}\n"));
        self.pending.extend_from_slice(reply.as_bytes());
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout_s: f64) -> Result<usize, LineError> {
        if self.pending.is_empty() {
            return Err(LineError::Timeout);
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        Ok(())
    }
}

fn driver(script: &[&[(&'static str, &'static str)]], config: PolytecConfig) -> PolytecDriver<ScriptedLine> {
    let line = ScriptedLine { script: script.concat().into_iter().collect(), pending: Vec::new() };
    PolytecDriver::new(line, RetryPolicy::default(), config).unwrap()
}

fn assert_script_done(driver: &PolytecDriver<ScriptedLine>) {
    assert!(driver.line().script.is_empty(), "script not played to the end: {:?}", driver.line().script);
}

/// Connecting to a unit with one velocity decoder at `VeloDec,0`.
const CONNECT: &[(&str, &str)] = &[
    ("Set,Interface,0,Echo,Off", ""),         // PLACE (old) setEcho
    ("Set,Controller,0,Remote,On", ""),       // PLACE (old) setRemote
    ("Get,Controller,0,Remote", "On\n"),      // PLACE (old) getRemote, the read-back
    ("GetDevInfo,VeloDec,0,Name", "VD-02\n"), // PLACE (old) get_dev_name
    ("GetDevInfo,VeloDec,0,Range", "1mm/s/V,5mm/s/V,25mm/s/V,125mm/s/V,1000mm/s/V\n"), // PLACE (old) get_dev_range
    ("GetDevInfo,SignalLevel,0,Value", "0,512\n"), // mock: the level's bounds
];

#[test]
fn a_session_is_byte_exact() {
    let mut ldv = driver(
        &[
            CONNECT,
            &[
                ("Set,VeloDec,0,Range,5mm/s/V", ""),                        // PLACE _set_range
                ("Get,VeloDec,0,Range", "5mm/s/V\n"),                       // PLACE _get_range
                ("Get,SignalLevel,0,Value", "384\n"),                       // PLACE _get_signal_level
                ("GetDevInfo,VeloDec,0,TrackingFilter", "Off,Slow,Fast\n"), // mock
                ("Set,VeloDec,0,TrackingFilter,Fast", ""),                  // mock
                ("Get,VeloDec,0,TrackingFilter", "Fast\n"),                 // mock
                ("GetDevInfo,Controller,0,Name", "OFV-5000 Vibrometer Controller\n"), // PLACE _get_controller_name
                ("Get,Controller,0,Version", "3.4\n"),                      // PLACE (old) getVersion
                ("Get,SensorHead,0,Name", "OFV-505\n"),                     // PLACE (old) PolytecSensorHead.getName
                ("Get,SensorHead,0,Version", "1.2\n"),                      // PLACE (old) PolytecSensorHead.getVersion
            ],
        ],
        PolytecConfig::default(),
    );
    let scale = ldv.set_velocity_range(0.05).unwrap();
    assert_eq!((scale.m_s_per_v, scale.full_scale_m_s), (0.005, 0.05));
    assert_eq!(ldv.signal_level().unwrap(), 0.75);
    ldv.set_tracking(Tracking::Fast).unwrap();
    let id = ldv.identify().unwrap();
    assert_eq!(id.vendor, "Polytec");
    assert_eq!(id.model, "OFV-5000 Vibrometer Controller; sensor head OFV-505; VeloDec,0 VD-02");
    assert_eq!(id.firmware, "controller 3.4; sensor head 1.2");
    assert_script_done(&ldv);
}

#[test]
fn the_decoder_named_in_the_file_is_found_by_query() {
    // PLACE's example layout: VD-08 at VeloDec,0 and VD-09 at VeloDec,1; the VD-09's ranges from PLACE's menu.
    let mut ldv = driver(
        &[&[
            ("Set,Interface,0,Echo,Off", ""),
            ("Set,Controller,0,Remote,On", ""),
            ("Get,Controller,0,Remote", "On\n"),
            ("GetDevInfo,VeloDec,0,Name", "VD-08\n"),
            ("GetDevInfo,VeloDec,1,Name", "VD-09\n"),
            ("GetDevInfo,VeloDec,1,Range", "1m/s/V,1m/s/V LP,500mm/s/V,5mm/s/V\n"),
            ("GetDevInfo,SignalLevel,0,Value", "0,100\n"),
            // 8 m/s wants 0.8 m/s/V or more: the plain 1 m/s/V range, not its LP variant.
            ("Set,VeloDec,1,Range,1m/s/V", ""),
            ("Get,VeloDec,1,Range", "1m/s/V\n"),
        ]],
        PolytecConfig { decoder: DecoderChoice::Name("VD-09".into()), ..PolytecConfig::default() },
    );
    assert_eq!(ldv.set_velocity_range(8.0).unwrap().m_s_per_v, 1.0);
    assert_script_done(&ldv);
}

#[test]
fn a_decoder_the_unit_lacks_is_named_with_what_it_has() {
    let mut ldv = driver(
        &[&[
            ("Set,Interface,0,Echo,Off", ""),
            ("Set,Controller,0,Remote,On", ""),
            ("Get,Controller,0,Remote", "On\n"),
            ("GetDevInfo,VeloDec,0,Name", "VD-08\n"),
            ("GetDevInfo,VeloDec,1,Name", "not Installed\n"), // PLACE (old): "not Installed"
        ]],
        PolytecConfig { decoder: DecoderChoice::Name("VD-09".into()), ..PolytecConfig::default() },
    );
    let err = ldv.set_velocity_range(0.1).unwrap_err();
    assert!(matches!(&err, VibrometerError::Device { message, .. } if message.contains("VeloDec,0 = VD-08")), "{err}");
    assert_script_done(&ldv);
}

#[test]
fn a_setting_that_does_not_take_is_sent_again_then_refused() {
    // OFV-3001 manual E.2.4: invalid settings are ignored; the read-back shows it.
    let mut ldv = driver(
        &[
            CONNECT,
            &[
                ("Set,VeloDec,0,Range,25mm/s/V", ""),
                ("Get,VeloDec,0,Range", "5mm/s/V\n"),
                ("Set,VeloDec,0,Range,25mm/s/V", ""),
                ("Get,VeloDec,0,Range", "5mm/s/V\n"),
            ],
        ],
        PolytecConfig::default(),
    );
    let err = ldv.set_velocity_range(0.2).unwrap_err();
    assert!(matches!(&err, VibrometerError::Device { message, .. } if message.contains("did not take")), "{err}");
    assert_script_done(&ldv);
}

#[test]
fn echo_is_skipped_and_garbage_is_retried_then_a_timeout() {
    let mut ldv = driver(
        &[
            CONNECT,
            &[
                // With echo on, the request comes back before its answer (OFV-3001 E.2.4, "Answer with ECHOON").
                ("Get,SignalLevel,0,Value", "Get,SignalLevel,0,Value\n256\n"),
                ("Get,SignalLevel,0,Value", "2x6\n"),
                ("Get,SignalLevel,0,Value", "\u{fffd}\n"),
                ("Get,SignalLevel,0,Value", ""),
            ],
        ],
        PolytecConfig::default(),
    );
    assert_eq!(ldv.signal_level().unwrap(), 0.5);
    let err = ldv.signal_level().unwrap_err();
    assert!(matches!(&err, VibrometerError::Timeout { detail, .. } if detail.starts_with("3 attempts")), "{err}");
    assert_script_done(&ldv);
}

/// Setting 125 mm/s/V and slow tracking, each read back; after a reconnect, the same again.
const RANGE_AND_TRACKING: &[(&str, &str)] = &[
    ("Set,VeloDec,0,Range,125mm/s/V", ""),
    ("Get,VeloDec,0,Range", "125mm/s/V\n"),
    ("GetDevInfo,VeloDec,0,TrackingFilter", "Off,Slow,Fast\n"),
    ("Set,VeloDec,0,TrackingFilter,Slow", ""),
    ("Get,VeloDec,0,TrackingFilter", "Slow\n"),
];

#[test]
fn reconnect_connects_again_and_reapplies_range_and_tracking() {
    let mut ldv = driver(&[CONNECT, RANGE_AND_TRACKING, CONNECT, RANGE_AND_TRACKING], PolytecConfig::default());
    ldv.set_velocity_range(1.0).unwrap();
    ldv.set_tracking(Tracking::Slow).unwrap();
    ldv.reconnect().unwrap();
    assert_script_done(&ldv);
}

#[test]
fn autofocus_polls_until_found_and_a_head_without_it_is_reported() {
    let connect_with_focus: Vec<(&str, &str)> = CONNECT
        .iter()
        .copied()
        .chain([
            ("GetDevInfo,SensorHead,0,AutoFocus", "Search\n"), // PLACE (old) getDevAutoFocus
            ("Set,SensorHead,0,AutoFocusSpan,Medium", ""),     // PLACE _autofocus_vibrometer
            ("Set,SensorHead,0,AutoFocus,Search", ""),         // PLACE _autofocus_vibrometer
            ("Get,SensorHead,0,AutoFocusResult", "Searching\n"), // PLACE polls until "Found"
            ("Get,SensorHead,0,AutoFocusResult", "Found\n"),
            ("Get,SignalLevel,0,Value", "512\n"),
        ])
        .collect();
    let leaked: &'static [(&'static str, &'static str)] = Box::leak(connect_with_focus.into_boxed_slice());
    let config = PolytecConfig { autofocus: Some(metaplate_ldv::FocusSpan::Medium), ..PolytecConfig::default() };
    let mut ldv = driver(&[leaked], config.clone());
    assert_eq!(ldv.signal_level().unwrap(), 1.0);
    assert_script_done(&ldv);

    let mut ldv = driver(&[CONNECT, &[("GetDevInfo,SensorHead,0,AutoFocus", "Not Available\n")]], config);
    let err = ldv.signal_level().unwrap_err();
    assert!(matches!(&err, VibrometerError::Device { message, .. } if message.contains("no autofocus")), "{err}");
}
