//! The mock lab: audio interface, actuators, plate, LDV and DAQ wired together on one virtual clock, from a scene.
