//! Wave-field analysis (being written).
