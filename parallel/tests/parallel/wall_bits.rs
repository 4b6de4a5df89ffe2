//! The wall's mobility in bands on a thread pool: the bits of one thread for
//! the assembly, the banded product and whole overdamped steps above the wall.

use hydrorattle::glam::DVec3;
use hydrorattle::mobility::wall;
use hydrorattle::parallel::{self, BANDED_MIN, Parallel, Serial, band_scratch, bands};
use hydrorattle::{
    BondSet, Hydro, Layout, NoForce, Params, Particle, ParticleSet, Real, Wall, step,
};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::Threads;

/// `n` spheres of radii 0.6 to 1.4 on a 12 x 12 grid of layers (spacing 3.2), the
/// lowest layer 1.8 above the wall `z = -1`.
fn grid(n: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
    let pos = (0..n)
        .map(|k| {
            let (i, j, l) = (k % 12, (k / 12) % 12, k / 144);
            [3.2 * i as f64, 3.2 * j as f64, 0.8 + 3.2 * l as f64]
        })
        .collect();
    let radius = (0..n)
        .map(|k| 0.6 + 0.8 * ((k * 7) % 11) as f64 / 10.0)
        .collect();
    (pos, radius)
}

fn bits<T: Real>(v: &[T::V3]) -> Vec<u64> {
    v.iter()
        .flat_map(|&p| T::xyz(p).map(|c| c.to_f64().to_bits()))
        .collect()
}

#[test]
fn wall_assembly_and_product_are_the_same_bits_on_any_thread_count() {
    let n = BANDED_MIN + 100;
    assert!(bands(n) > 1);
    let (p, radius) = grid(n);
    let pos: Vec<DVec3> = p.iter().map(|&x| DVec3::from(x)).collect();
    let tri = n * (n + 1) / 2;
    let mut mu = vec![f64::M3_ZERO; tri];
    wall::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, -1.0, &pos, &radius, &mut mu).unwrap();
    let x: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new((i as f64).cos(), 0.5, 1.0 / (1.0 + i as f64)))
        .collect();
    let mut z = vec![DVec3::ZERO; band_scratch(n)];
    let mut serial = vec![DVec3::ZERO; n];
    parallel::product::<f64>(&Serial, &mu, n, &x, &mut serial, &mut z);
    for t in [1, 2, 3, 4] {
        let pool = Threads::new(t).unwrap();
        let par: &dyn Parallel = &pool;
        let mut mu2 = vec![f64::M3_ZERO; tri];
        wall::assemble::<f64>(par, Hydro::Rpy, 1.0, -1.0, &pos, &radius, &mut mu2).unwrap();
        assert!(mu2 == mu, "{t} threads: assembly");
        let mut y = vec![DVec3::ZERO; n];
        parallel::product::<f64>(par, &mu2, n, &x, &mut y, &mut z);
        assert_eq!(
            bits::<f64>(&y),
            bits::<f64>(&serial),
            "{t} threads: product"
        );
    }
}

/// Two overdamped steps of the grid (`N` spheres) settling towards the wall; with
/// `chains`, the spheres of each grid row held in a chain (Krylov solves), with `free`
/// matrix-free.
fn steps<T: Real, const N: usize>(par: &dyn Parallel, chains: bool, free: bool) -> Vec<u64> {
    let (p, radius) = grid(N);
    let list: Vec<Particle<T>> = p
        .iter()
        .zip(&radius)
        .map(|(&x, &a)| Particle::new(T::v3_from(x), T::from_f64(a), T::from_f64(2.0)))
        .collect();
    let mut ps = Box::new(ParticleSet::<T, N>::from_slice(&list, false).unwrap());
    let mut bonds = Box::new(BondSet::<T, N>::new());
    for k in (0..N - 1).filter(|k| chains && k % 12 != 11) {
        bonds.push_current(k, k + 1, &ps.pos[..N]).unwrap();
    }
    let mut params = Params::<T>::new(T::from_f64(0.01));
    params.wall = Some(Wall::new(T::from_f64(-1.0)));
    params.matrix_free = free;
    let mut store = Buffers::<T>::new(Layout::for_params(&params, N, bonds.len()));
    let mut ws = store.workspace().with_parallel(par);
    for _ in 0..2 {
        step(&mut ps, &bonds, &params, &mut ws, &mut NoForce).unwrap();
    }
    bits::<T>(&ps.pos[..N])
}

#[test]
fn steps_above_the_wall_are_the_same_bits_on_any_thread_count() {
    const N: usize = BANDED_MIN + 40;
    let one = steps::<f64, N>(&Serial, false, false);
    let one32 = steps::<f32, N>(&Serial, false, false);
    for t in [2, 3] {
        let pool = Threads::new(t).unwrap();
        assert_eq!(steps::<f64, N>(&pool, false, false), one, "{t} threads");
        assert_eq!(
            steps::<f32, N>(&pool, false, false),
            one32,
            "{t} threads, f32"
        );
    }
}

/// Matrix-free steps above the wall (their products in bands, `wall::free_product`,
/// also the Krylov constraint products): the stored steps' bits, on any thread count.
#[test]
fn matrix_free_steps_above_the_wall_are_the_stored_bits_on_any_thread_count() {
    const N: usize = BANDED_MIN + 40;
    let stored = steps::<f64, N>(&Serial, true, false);
    assert_eq!(steps::<f64, N>(&Serial, true, true), stored, "1 thread");
    let pool = Threads::new(2).unwrap();
    assert_eq!(steps::<f64, N>(&pool, true, true), stored, "2 threads");
}

/// `wall::free_product` of unit viscosity, RPY, the wall at `z = -1`.
fn free(
    par: &dyn Parallel,
    pos: &[DVec3],
    radius: &[f64],
    x: &[DVec3],
    y: &mut [DVec3],
    z: &mut [DVec3],
) -> Result<(), hydrorattle::ParticleError> {
    wall::free_product::<f64>(par, Hydro::Rpy, 1.0, -1.0, pos, radius, x, y, z)
}

/// The wall's matrix-free product in bands (`wall::free_product`): the stored banded
/// product's bits on any thread count, `tt_product`'s bits below `BANDED_MIN` rows, and
/// `tt_product`'s first error (a sphere below the wall, nested spheres).
#[test]
fn wall_matrix_free_product_has_the_stored_bits_on_any_thread_count() {
    for n in [BANDED_MIN / 2, BANDED_MIN + 100] {
        let (p, radius) = grid(n);
        let pos: Vec<DVec3> = p.iter().map(|&x| DVec3::from(x)).collect();
        let mut mu = vec![f64::M3_ZERO; n * (n + 1) / 2];
        wall::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, -1.0, &pos, &radius, &mut mu).unwrap();
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new((i as f64).cos(), 0.5, 1.0 / (1.0 + i as f64)))
            .collect();
        let mut z = vec![DVec3::ZERO; band_scratch(n)];
        let mut stored = vec![DVec3::ZERO; n];
        parallel::product::<f64>(&Serial, &mu, n, &x, &mut stored, &mut z);
        if bands(n) == 1 {
            let mut serial = vec![DVec3::ZERO; n];
            wall::tt_product::<f64>(Hydro::Rpy, 1.0, -1.0, &pos, &radius, &x, &mut serial).unwrap();
            assert_eq!(bits::<f64>(&serial), bits::<f64>(&stored), "N = {n}");
        }
        for t in [1, 2, 3] {
            let pool = Threads::new(t).unwrap();
            let mut y = vec![DVec3::ZERO; n];
            let r = free(&pool, &pos, &radius, &x, &mut y, &mut z);
            r.unwrap();
            assert_eq!(
                bits::<f64>(&y),
                bits::<f64>(&stored),
                "N = {n}, {t} threads"
            );
        }
    }
    // Errors: nested spheres (two of them, the first in row order wins), then a sphere
    // below the wall, which is reported first.
    let n = BANDED_MIN + 100;
    let (p, radius) = grid(n);
    let mut pos: Vec<DVec3> = p.iter().map(|&x| DVec3::from(x)).collect();
    pos[580] = pos[30];
    pos[400] = pos[300];
    let (x, mut y, mut z) = (
        vec![DVec3::ONE; n],
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; band_scratch(n)],
    );
    let pool = Threads::new(2).unwrap();
    for sink in [false, true] {
        if sink {
            pos[450].z = -2.0;
        }
        let want = wall::tt_product::<f64>(Hydro::Rpy, 1.0, -1.0, &pos, &radius, &x, &mut y);
        let got = free(&pool, &pos, &radius, &x, &mut y, &mut z);
        assert!(want.is_err());
        assert_eq!(got, want, "below the wall: {sink}");
    }
}
