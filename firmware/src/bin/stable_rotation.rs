//! Figure 1 (c) chain, `Method::RattleStable` with rotation, in f32 (see the crate docs).
#![no_std]
#![no_main]

hydrorattle_firmware::firmware!("stable_rotation", hydrorattle::Method::RattleStable, true);
