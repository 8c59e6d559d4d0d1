use metaplate_keypad_protocol::*;

#[test]
fn keys_type_their_characters() {
    let c = |usage: u8| Key::new(usage).and_then(Key::character);
    assert_eq!((c(0x04), c(0x1D), c(0x1E), c(0x26), c(0x27)), (Some('a'), Some('z'), Some('1'), Some('9'), Some('0')));
    assert_eq!((c(0x59), c(0x61), c(0x62), c(0x2C)), (Some('1'), Some('9'), Some('0'), Some(' ')));
    assert_eq!((c(0x28), c(0xE0)), (None, None));
}

#[test]
fn key_codes_below_four_are_not_keys() {
    assert_eq!(Key::new(0x00), None);
    assert_eq!(Key::new(0x03), None);
    assert_eq!(Key::new(0x04).map(Key::usage), Some(0x04));
    assert!(Key::new(0xE0).is_some_and(Key::is_modifier));
    assert!(Key::new(0xE7).is_some_and(Key::is_modifier));
    assert!(!Key::new(0xE8).is_some_and(Key::is_modifier));
    assert!(!Key::new(0xDF).is_some_and(Key::is_modifier));
}
