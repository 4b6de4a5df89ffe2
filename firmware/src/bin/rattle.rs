//! Figure 1 (c) chain, `Method::Rattle`, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("rattle", hydrorattle::Method::Rattle, false);
