//! Recipes: actuator calibration and the grid scan, as resumable state machines over capability traits and the store.
