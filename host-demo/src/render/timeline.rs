//! State against time.
