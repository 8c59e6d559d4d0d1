use metaplate_core::daq::*;

fn integrity(packets_lost: u64, samples_missing: u64, overrun: bool, clipped: bool) -> BlockIntegrity {
    BlockIntegrity { packets_lost, samples_missing, overrun, clipped }
}

#[test]
fn contiguity_ignores_clipping_only() {
    assert!(integrity(0, 0, false, false).is_contiguous());
    assert!(integrity(0, 0, false, true).is_contiguous());
    assert!(!integrity(1, 0, false, false).is_contiguous());
    assert!(!integrity(0, 1, false, false).is_contiguous());
    assert!(!integrity(0, 0, true, false).is_contiguous());
}

#[test]
fn block_length_is_per_channel() {
    let block = DaqBlock {
        first_sample_index: 0,
        volts: vec![vec![0.0; 3], vec![1.0; 3]],
        integrity: BlockIntegrity::default(),
    };
    assert_eq!(block.len_samples(), 3);
    let empty = DaqBlock { first_sample_index: 0, volts: vec![], integrity: BlockIntegrity::default() };
    assert_eq!(empty.len_samples(), 0);
}
