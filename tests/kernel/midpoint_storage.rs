//! The Brownian midpoint's mobility storage: golden digests of Lanczos-noise steps
//! with the midpoint drift (the paper's 25-bead helix, `K` steps at `kT = 1`), pinned
//! while the midpoint's mobility `mu(x~)` was assembled into nine-scalar blocks, in
//! free space, in a periodic box and above a wall, with the dense and the Krylov
//! solver, `Overdamped` and `Springs`, both precisions. Free space and the box now keep
//! it in six-scalar symmetric blocks (`linalg::Sym`): the digests must not move,
//! because each of their blocks is symmetric in bits and `Sym`'s products do the
//! nine-scalar block's arithmetic in glam's order (`linalg::block`'s tests).
//!
//! Each step runs on a workspace whose every scalar is NaN before the step (its
//! indices zero), so a read of storage the step did not write first (a factor slot the
//! midpoint no longer uses, the start's mobility instead of the midpoint's) turns the
//! positions to NaN or moves the digest: the midpoint must read the mobility it
//! assembled at `x~`. Regenerate only for a deliberate change of the arithmetic.
//!
//! `Springs` in the box has no constraints to project the noise onto, so its
//! `Drift::Midpoint` is the uncorrected draw there (the box's mobility has zero
//! divergence; `tests/kernel/periodic_brownian.rs`): its two digests were re-pinned when that
//! change was made, from `0xd827b534df4945db` (f64) and `0xebff16e658b99548` (f32), and
//! they now pin the uncorrected Lanczos draw on a poisoned workspace.

use crate::common;

use common::*;
use hydrorattle::noise::reduced;
use hydrorattle::{
    BondSet, Brownian, Drift, Layout, Method, NoForce, Noise, NoiseSqrt, Params, ParticleSet,
    Periodic, Real, SolverKind, Wall, Workspace,
};

const K: usize = 4;
const DT: f64 = 0.01;

/// Where the step runs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Place {
    Free,
    Box,
    Wall,
}

/// `(place, method, solver, precision, digest)`.
const PINS: [(Place, Method, SolverKind, &str, u64); 16] = [
    (
        Place::Free,
        Method::Overdamped,
        SolverKind::Krylov,
        "f64",
        0x5398_de93_0d14_97d5,
    ),
    (
        Place::Free,
        Method::Overdamped,
        SolverKind::Newton,
        "f64",
        0x8596_c98e_9fb1_0a54,
    ),
    (
        Place::Free,
        Method::Springs,
        SolverKind::Auto,
        "f64",
        0x44e0_0030_9ace_f729,
    ),
    (
        Place::Box,
        Method::Overdamped,
        SolverKind::Krylov,
        "f64",
        0x4a6f_b4a0_19b4_649b,
    ),
    (
        Place::Box,
        Method::Overdamped,
        SolverKind::Newton,
        "f64",
        0xb107_0894_a1ca_3b5d,
    ),
    (
        Place::Wall,
        Method::Overdamped,
        SolverKind::Krylov,
        "f64",
        0x7215_d0c8_95a2_605a,
    ),
    (
        Place::Wall,
        Method::Overdamped,
        SolverKind::Newton,
        "f64",
        0x3542_9c8f_3590_bab5,
    ),
    (
        Place::Box,
        Method::Springs,
        SolverKind::Auto,
        "f64",
        0xcdba_9f3e_e939_d44d,
    ),
    (
        Place::Free,
        Method::Overdamped,
        SolverKind::Krylov,
        "f32",
        0x6b22_8bcd_be4f_ad40,
    ),
    (
        Place::Free,
        Method::Overdamped,
        SolverKind::Newton,
        "f32",
        0xd2a1_00b6_ae00_9554,
    ),
    (
        Place::Free,
        Method::Springs,
        SolverKind::Auto,
        "f32",
        0xe5bd_5555_8428_efbd,
    ),
    (
        Place::Box,
        Method::Overdamped,
        SolverKind::Krylov,
        "f32",
        0x4e34_94b3_9005_7122,
    ),
    (
        Place::Box,
        Method::Overdamped,
        SolverKind::Newton,
        "f32",
        0xaf20_e11f_dded_584a,
    ),
    (
        Place::Wall,
        Method::Overdamped,
        SolverKind::Krylov,
        "f32",
        0x26a1_faa1_309b_f63c,
    ),
    (
        Place::Wall,
        Method::Overdamped,
        SolverKind::Newton,
        "f32",
        0x5873_3c9c_7e98_2b8d,
    ),
    (
        Place::Box,
        Method::Springs,
        SolverKind::Auto,
        "f32",
        0x07dc_97ba_29af_64f9,
    ),
];

/// Lanczos noise, midpoint drift, `kT = 1`, no gravity, at `place`.
fn thermal<T: Real>(place: Place, method: Method, kind: SolverKind) -> Params<T> {
    let mut p = params::<T>(DT, method, kind);
    p.gravity = T::V3_ZERO;
    p.allow_overlap = true;
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift: Drift::Midpoint,
    });
    p.noise_sqrt = NoiseSqrt::Lanczos;
    p.spring_stiffness = T::from_f64(50.0);
    match place {
        Place::Free => {}
        Place::Box => p.periodic = Some(Periodic::new([T::from_f64(20.0); 3]).unwrap()),
        Place::Wall => p.wall = Some(Wall::new(T::from_f64(-8.0))),
    }
    p
}

fn digest<T: Real>(place: Place, method: Method, kind: SolverKind) -> u64 {
    let scene = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, 25> = particles(&scene);
    let bonds: BondSet<T, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
    let p = thermal::<T>(place, method, kind);
    let l = Layout::for_params(&p, 25, 24);
    let mut blocks = vec![T::M3_ZERO; l.blocks];
    let mut vectors = vec![T::V3_ZERO; l.vectors];
    let mut scalars = vec![T::ZERO; l.scalars];
    let (mut indices, mut links) = (vec![0; l.indices], vec![bonds.as_slice()[0]; l.links]);
    let mut noise = Noise::new(17);
    for k in 0..K {
        // Poison everything the step may read before it writes.
        let nan = T::from_f64(f64::NAN);
        let v = T::v3(nan, nan, nan);
        blocks.fill(T::m3_cols(v, v, v));
        vectors.fill(v);
        scalars.fill(nan);
        indices.fill(0);
        let mut ws = Workspace::new(&mut blocks, &mut vectors, &mut scalars, &mut indices)
            .with_links(&mut links);
        let r = step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise)
            .unwrap_or_else(|e| panic!("{place:?} {method:?} {kind:?} step {k}: {e}"));
        assert!(r.noise_iterations > 1, "{r:?}");
        if method == Method::Overdamped {
            assert!(r.velocity_iterations > 0, "no midpoint projection: {r:?}");
        }
    }
    for i in 0..25 {
        assert!(f64s::<T>(ps.pos[i]).iter().all(|x| x.is_finite()));
    }
    state_digest(&ps)
}

fn golden<T: Real>() {
    let precision = if is_single::<T>() { "f32" } else { "f64" };
    let mut mismatches = Vec::new();
    for &(place, method, kind, prec, pin) in PINS.iter().filter(|e| e.3 == precision) {
        let got = digest::<T>(place, method, kind);
        eprintln!(
            "midpoint {place:?} {method:?} {kind:?} {prec}: got {got:#018x}, pinned {pin:#018x}"
        );
        if got != pin {
            mismatches.push((place, method, kind, got));
        }
    }
    assert!(
        mismatches.is_empty(),
        "midpoint digests changed: {mismatches:x?}"
    );
}

both_precisions! {
    midpoint_golden_digest => golden;
}

/// The midpoint's storage by Lanczos noise: six scalars a pair where the mobility's
/// blocks are symmetric (free space, a box) instead of the nine of a Cholesky factor's
/// block, nine above a wall, the reduced copy (an `f64` kernel of `REDUCED_MIN` beads
/// and more, free space) in slots of its own; by Cholesky the factor's blocks as
/// before. Prints the bytes of each workspace, and those of the nine-scalar midpoint.
#[test]
fn midpoint_storage_is_sized_for_its_blocks() {
    fn check<T: Real>(place: Place, method: Method, n: usize) {
        let tri = n * (n + 1) / 2;
        let mut p = thermal::<T>(place, method, SolverKind::Krylov);
        let lanczos = Layout::for_params(&p, n, n - 1);
        p.noise_sqrt = NoiseSqrt::Cholesky;
        let cholesky = Layout::for_params(&p, n, n - 1);
        p.brownian = p.brownian.map(|b| Brownian {
            drift: Drift::Uncorrected,
            ..b
        });
        p.noise_sqrt = NoiseSqrt::Lanczos;
        // By Lanczos without a midpoint: no factor, no midpoint storage, no copy.
        let bare = Layout::for_params(&p, n, n - 1);
        assert_eq!(
            cholesky.blocks,
            bare.blocks + tri,
            "{place:?} {method:?} {n}"
        );
        let copy = match place {
            Place::Free if !is_single::<T>() && n >= reduced::REDUCED_MIN => reduced::slots(n),
            _ => 0,
        };
        let nine = Layout {
            blocks: bare.blocks + tri + copy.saturating_sub(tri),
            scalars: lanczos.scalars - if place == Place::Wall { 0 } else { 6 * tri },
            ..lanczos
        };
        let (mid_blocks, mid_scalars) = match place {
            Place::Wall => (tri, 0),
            _ => (0, 6 * tri),
        };
        assert_eq!(lanczos.blocks, bare.blocks + mid_blocks + copy);
        assert_eq!(lanczos.scalars, bare.scalars + mid_scalars);
        // The copy: 24 bytes a pair (three `f64` slot entries) and at most eleven
        // blocks of padding a row.
        assert!(
            9 * copy <= 3 * tri + 33 * n,
            "copy {copy} slots for {tri} pairs"
        );
        eprintln!(
            "{place:?} {method:?} n {n} {}: {} bytes by Lanczos and the midpoint \
             ({} with its mobility in the factor's nine-scalar blocks), {} by Cholesky",
            core::any::type_name::<T>(),
            lanczos.bytes::<T>(),
            nine.bytes::<T>(),
            cholesky.bytes::<T>()
        );
    }
    for n in [25, 4096] {
        for (place, method) in [
            (Place::Free, Method::Overdamped),
            (Place::Free, Method::Springs),
            (Place::Box, Method::Overdamped),
            (Place::Wall, Method::Overdamped),
        ] {
            check::<f64>(place, method, n);
            check::<f32>(place, method, n);
        }
    }
}
