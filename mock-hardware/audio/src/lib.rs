//! The mock audio interface: a PCM sink on the virtual clock with output latency, clock offset and underruns.
