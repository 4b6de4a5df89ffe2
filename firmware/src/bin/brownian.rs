//! Figure 1 (c) chain, `Method::Overdamped` at `kT = 0.5` (midpoint drift, seed 7), in
//! f32: the C example's Brownian run (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("brownian", hydrorattle::Method::Overdamped, false, true);
