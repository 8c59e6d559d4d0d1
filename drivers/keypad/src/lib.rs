//! HID response keypad driver (hidapi) for perceptual experiments.
