//! Host-side driver for the hydrorattle kernel.
