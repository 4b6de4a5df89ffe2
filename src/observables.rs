//! Observables (filled in below).
