//! Figure 1 (c) chain, `Method::Overdamped2`, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("overdamped2", hydrorattle::Method::Overdamped2, false);
