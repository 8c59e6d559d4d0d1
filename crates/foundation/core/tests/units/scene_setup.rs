use metaplate_core::scene::*;

#[test]
fn a_swap_exchanges_the_two_channels_only() {
    let setup = SetupSpec { swapped_actuators: Some([2, 5]), ..SetupSpec::default() };
    assert_eq!(setup.physical_channels(&[0, 1, 2, 3, 4, 5]), [0, 1, 5, 3, 4, 2]);
    assert_eq!(SetupSpec::default().physical_channels(&[0, 1, 2]), [0, 1, 2]);
    assert!(SetupSpec::default().is_correct() && !setup.is_correct());
}
