use metaplate_core::aim::*;

#[test]
fn no_aimer_refuses_and_only_link_failures_suggest_reconnect() {
    let mut none = NoAimer { detail: "add an [aim] section".into() };
    assert!(matches!(none.aim_at(0.0, 0.0), Err(AimError::Unavailable { .. })));
    assert!(AimError::Disconnected { reason: "gone".into() }.suggests_reconnect());
    assert!(!AimError::Device { message: "limit".into() }.suggests_reconnect());
}

#[test]
fn rectangle_check_names_the_failure() {
    assert_eq!(check_within(0.5, -0.5, 0.5), Ok(()));
    assert!(matches!(check_within(0.5001, 0.0, 0.5), Err(AimError::Unreachable { .. })));
    assert!(matches!(check_within(f64::NAN, 0.0, 0.5), Err(AimError::InvalidArgument { .. })));
}
