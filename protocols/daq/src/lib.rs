//! DAQ USB bulk protocol (being written).
