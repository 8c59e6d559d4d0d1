//! LDV controller protocol (being written).
