use std::cell::Cell;
use std::rc::Rc;

use metaplate_daq::transport::*;

/// A handle of a fake device that can be claimed once at a time, as a USB interface.
struct Claim(Rc<Cell<u32>>);

impl Drop for Claim {
    fn drop(&mut self) {
        self.0.set(self.0.get() - 1);
    }
}

/// Opens a claim, refusing (as the kernel does for a claimed interface) while another one is alive.
fn claim(alive: &Rc<Cell<u32>>) -> Result<Claim, String> {
    if alive.get() > 0 {
        return Err("interface busy: still claimed by the old handle".into());
    }
    alive.set(alive.get() + 1);
    Ok(Claim(Rc::clone(alive)))
}

#[test]
fn a_reopen_releases_the_old_handle_before_claiming_again() {
    let alive = Rc::new(Cell::new(0));
    let mut slot = claim(&alive).ok();
    assert!(slot.is_some());
    for _ in 0..3 {
        assert_eq!(reopen_dropping_first(&mut slot, || claim(&alive)), Ok(()));
        assert_eq!(alive.get(), 1);
    }
    // Opening before dropping (the old `*self = Self::open(..)`) is refused by the same fake device.
    assert!(claim(&alive).is_err());
}

#[test]
fn a_failed_reopen_leaves_the_transport_closed() {
    let alive = Rc::new(Cell::new(0));
    let mut slot = claim(&alive).ok();
    assert_eq!(reopen_dropping_first(&mut slot, || Err::<Claim, _>("device absent")), Err("device absent"));
    assert!(slot.is_none());
    assert_eq!(alive.get(), 0);
}
