//! Figure 1 (c) chain, `Method::Springs`, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("springs", hydrorattle::Method::Springs, false);
