use metaplate_core::vibrometer::*;

#[test]
fn only_link_failures_suggest_reconnect() {
    let timeout = VibrometerError::Timeout { command: "Get,SignalLevel,0,Value".into(), detail: "3 attempts".into() };
    let gone = VibrometerError::Disconnected { reason: "port vanished".into() };
    let device = VibrometerError::Device { code: 6, message: "range not on the decoder".into() };
    let bad = VibrometerError::InvalidArgument { detail: "max_velocity_m_s = NaN".into() };
    assert!(timeout.suggests_reconnect() && gone.suggests_reconnect());
    assert!(!device.suggests_reconnect() && !bad.suggests_reconnect());
    assert_eq!(device.to_string(), "vibrometer error 6: range not on the decoder");
}
