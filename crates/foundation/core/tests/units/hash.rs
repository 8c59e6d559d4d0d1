use metaplate_core::hash::*;

#[test]
fn matches_the_published_test_vectors() {
    // From the FNV reference (Fowler, Noll, Vo): the empty string, "a" and "foobar".
    assert_eq!(fnv1a_64([]), 0xcbf2_9ce4_8422_2325);
    assert_eq!(fnv1a_64(*b"a"), 0xaf63_dc4c_8601_ec8c);
    assert_eq!(fnv1a_64(*b"foobar"), 0x8594_4171_f739_67e8);
}
