//! The pair searches with a cell list (`cell_list`, from `CELLS_MIN` spheres on) find
//! the pairs every-pair scans find, in the same order: a settling suspension with hard
//! contacts gives the same bits as the all-pairs search. The golden digests below were
//! recorded with every pair (first at commit 58ae007, before the cell list; again when
//! the one-sided contact solve changed the free and wall trajectories, when Krylov's
//! preconditioner on the constraint graph changed them, and when `SolverKind::Auto` took
//! Newton for contacts up to `PILE_NEWTON_MAX` spheres, with `CELLS_MIN = usize::MAX`);
//! here 160 spheres are past `CELLS_MIN`, so the cell list runs.
//! `cargo test --release --test kernel pair_search::`. Each case also checks every step for
//! overlap by its own scan.

use crate::common;

use common::boxes::config_radii;
use common::fuzz::Rng;
use common::*;
use hydrorattle::{
    BondSet, Contacts, Hydro, Layout, Method, NoForce, Params, ParticleSet, Periodic, Real,
    SolverKind, Wall, cell_list, step,
};
use hydrorattle_heap::Buffers;

const N: usize = 160;

/// Where the suspension settles.
#[derive(Clone, Copy, Debug)]
enum Place {
    /// Free space, RPY.
    Free,
    /// Above a wall at `z = 0`.
    Wall,
    /// A periodic box (free draining: the pair search is what is tested).
    Box,
}

/// `N` polydisperse spheres (radii 0.5 to 1, densities 1.5 to 9) placed apart in a
/// region of edge `size`, settling with hard contacts for `steps` steps; the digest of
/// the end state and of every step's contact count, and the most contacts held.
fn settle<T: Real>(place: Place, steps: usize) -> (u64, u32) {
    const { assert!(N >= cell_list::CELLS_MIN, "the cell list must be in use") };
    let size = [14.0, 14.0, 14.0];
    let (pos, rad) = config_radii(N, 27, size, [0.5, 1.0], false);
    assert_eq!(pos.len(), N);
    let mut rng = Rng(5);
    let lift = match place {
        Place::Wall => 1.0,
        _ => 0.0,
    };
    let spheres: Vec<Sphere> = pos
        .iter()
        .zip(&rad)
        .map(|(&p, &a)| Sphere {
            pos: [p[0], p[1], p[2] + lift],
            radius: a,
            density: rng.range(1.5, 9.0),
        })
        .collect();
    let mut ps: ParticleSet<T, N> = particles(&spheres);
    let bonds = BondSet::<T, 1>::new();
    let mut p: Params<T> = params(0.15, Method::Overdamped, SolverKind::Auto);
    p.contacts = Some(Contacts::new(4 * N));
    p.solver.tolerance = T::from_f64(pick::<T>(1e-5, 1e-10));
    p.gravity = v3::<T>(0.0, 0.0, -1.0);
    p.fluid_density = T::ONE;
    match place {
        Place::Free => {}
        Place::Wall => p.wall = Some(Wall::new(T::ZERO)),
        Place::Box => {
            p.hydro = Hydro::FreeDraining;
            p.periodic = Some(Periodic::new(size.map(T::from_f64)).unwrap());
        }
    }
    let mut store = Buffers::<T>::new(Layout::for_params(&p, N, 0));
    let mut ws = store.workspace();
    let tol = p.solver.tolerance.to_f64();
    let (mut counts, mut most) = (vec![], 0);
    for k in 0..steps {
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("{place:?} step {k}: {e}"));
        counts.push(u64::from(r.contacts));
        most = most.max(r.contacts);
        for i in 0..N {
            for j in 0..i {
                let mut d = sub(f64s::<T>(ps.pos[i]), f64s::<T>(ps.pos[j]));
                if let Place::Box = place {
                    d = common::boxes::min_image(d, size);
                }
                let sigma = (ps.radius[i] + ps.radius[j]).to_f64();
                assert!(
                    norm(d) >= sigma * (1.0 - 2.0 * tol),
                    "{place:?} step {k}: {i}-{j} overlap"
                );
            }
        }
    }
    (fnv1a([state_digest(&ps)].into_iter().chain(counts)), most)
}

fn check<T: Real>(golden: [u64; 3]) {
    let places = [Place::Free, Place::Wall, Place::Box];
    let got = places.map(|place| {
        let (d, most) = settle::<T>(place, 12);
        println!("{place:?}: digest {d:#018x}, at most {most} contacts");
        assert!(
            most >= 5,
            "{place:?}: too few contacts ({most}) to test the search"
        );
        d
    });
    assert_eq!(got, golden, "{got:#018x?}");
}

#[test]
fn same_bits_as_every_pair_f64() {
    check::<f64>([
        0x2914_7954_5516_74ca,
        0x994a_4208_3ece_2077,
        0xf798_1eb8_b1b6_7a8e,
    ]);
}

#[test]
fn same_bits_as_every_pair_f32() {
    check::<f32>([
        0x4066_31a8_c2f8_5176,
        0x743c_0d5c_6d28_6c0d,
        0x1c74_bfbc_9ec7_86e6,
    ]);
}
