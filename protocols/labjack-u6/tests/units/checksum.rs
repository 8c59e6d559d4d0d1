use metaplate_u6_protocol::checksum::*;

#[test]
fn labjackpython_docstring_example() {
    // `setChecksum` docstring in LabJackPython.py: [0, 0xf8, 0x03, 0x0b, 0, 0, 0, 0, 0, 0, 0, 0] -> byte 0 = 7.
    let mut p = [0u8, 0xf8, 0x03, 0x0b, 0, 0, 0, 0, 0, 0, 0, 0];
    seal(&mut p);
    assert_eq!(p[0], 7);
    assert_eq!(&p[4..6], &[0, 0]);
    assert!(is_valid(&p));
}

#[test]
fn normal_commands_cover_every_byte() {
    // StreamStart is `A8 A8` (User's Guide 5.2.13): its checksum is its one other byte.
    let mut p = [0u8, 0xa8];
    seal(&mut p);
    assert_eq!(p, [0xa8, 0xa8]);
    // A sum over 0xff folds: 0xff + 0x02 = 0x101 -> 0x01 + 0x01 = 0x02.
    assert_eq!(checksum8(&[0xff, 0x02]), 0x02);
}
