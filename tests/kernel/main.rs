//! The kernel's integration tests, one binary: each file of this folder is a module.
//! A single binary links the kernel once instead of once a file, which is most of the
//! build's time. Run one file's tests with its module path as the filter:
//! `cargo test --release --test kernel jam::`.
//!
//! A new test file `tests/kernel/NAME.rs` is added by one line below, `mod NAME;`
//! (with `#[cfg(feature = "...")]` in front if it needs a feature), and
//! `use crate::common;` inside it for the shared helpers.

#[macro_use]
mod common;

mod alloc;
mod auto_boundary;
#[cfg(feature = "periodic")]
mod box_copy;
#[cfg(feature = "periodic")]
mod box_resolution;
mod bridge;
mod brownian;
mod budget;
#[cfg(feature = "contacts")]
mod contacts;
#[cfg(all(feature = "periodic", feature = "contacts"))]
mod contacts_brownian;
mod determinism;
mod docs;
mod dynamics;
#[cfg(feature = "fast-free")]
mod fast_keep;
#[cfg(feature = "fast-free")]
mod fast_rotation;
#[cfg(feature = "fast-free")]
mod fast_step;
mod free_draining;
#[cfg(feature = "fast-free")]
mod free_fast;
#[cfg(feature = "fast-free")]
mod free_fast_grand;
#[cfg(feature = "fast-free")]
mod free_o2;
mod fuzz_step;
#[cfg(feature = "periodic")]
mod grand_cost;
mod helix;
mod inertial_thermal;
#[cfg(feature = "contacts")]
mod jam;
mod krylov;
mod lanczos;
mod lanczos_chain;
mod matrix_free;
mod midpoint_storage;
mod mobility;
#[cfg(feature = "near")]
mod near;
#[cfg(all(feature = "near", feature = "periodic"))]
mod near_box;
#[cfg(feature = "near")]
mod near_brownian;
#[cfg(all(feature = "near", feature = "periodic"))]
mod near_con;
#[cfg(all(feature = "near", feature = "wall"))]
mod near_con_brownian;
#[cfg(all(feature = "near", feature = "periodic"))]
mod near_contacts;
#[cfg(all(feature = "near", feature = "fast-free"))]
mod near_fast;
#[cfg(all(feature = "near", feature = "periodic"))]
mod near_iter;
mod near_iter_brownian;
#[cfg(all(feature = "near", feature = "pse"))]
mod near_pse;
#[cfg(feature = "near")]
mod near_step;
mod observables;
mod ordered_factor;
#[cfg(all(feature = "contacts", feature = "periodic", feature = "wall"))]
mod pair_search;
#[cfg(feature = "periodic")]
mod periodic;
mod periodic_brownian;
mod periodic_digest;
#[cfg(all(feature = "periodic", feature = "contacts"))]
mod periodic_step;
#[cfg(all(feature = "contacts", feature = "wall"))]
mod pile_factor;
#[cfg(all(feature = "contacts", feature = "wall"))]
mod pile_krylov;
mod pins;
#[cfg(feature = "pse")]
mod pse;
#[cfg(feature = "pse")]
mod pse_brownian;
#[cfg(feature = "pse")]
mod pse_grand;
#[cfg(feature = "pse")]
mod pse_limits;
mod pse_step;
mod reference;
mod resolution;
mod robustness;
#[cfg(feature = "slit")]
mod slit;
mod springs_thermal;
mod stability;
mod states;
#[cfg(feature = "near")]
mod stokesian;
#[cfg(all(feature = "near", feature = "periodic"))]
mod stokesian_box;
#[cfg(feature = "near")]
mod stokesian_far;
#[cfg(feature = "near")]
mod stokesian_iter;
mod tensions;
mod transactional;
mod wall;
mod wall_barometric;
mod wall_contacts;
mod weak_order;
