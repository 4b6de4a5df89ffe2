//! Figure 1 (c) chain, `Method::RattleStable`, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("stable", hydrorattle::Method::RattleStable, false);
