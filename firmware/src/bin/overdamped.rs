//! Figure 1 (c) chain, `Method::Overdamped`, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("overdamped", hydrorattle::Method::Overdamped, false);
