//! pysindy-compatible STLSQ (to be written).
