//! Record and replay of device sessions: transports that write cassettes, and transports that play them back (with faults).
