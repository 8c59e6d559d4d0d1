//! Wave-field control: propagation matrices, inverse filtering, time reversal, targets and drive-signal rendering.
