//! The wall's mobility (issue 21) in bands on a thread pool: the bits of one thread for
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

/// Two overdamped steps of the grid (`N` spheres) settling towards the wall.
fn steps<T: Real, const N: usize>(par: &dyn Parallel) -> Vec<u64> {
    let (p, radius) = grid(N);
    let list: Vec<Particle<T>> = p
        .iter()
        .zip(&radius)
        .map(|(&x, &a)| Particle::new(T::v3_from(x), T::from_f64(a), T::from_f64(2.0)))
        .collect();
    let mut ps = Box::new(ParticleSet::<T, N>::from_slice(&list, false).unwrap());
    let bonds = BondSet::<T, 1>::new();
    let mut params = Params::<T>::new(T::from_f64(0.01));
    params.wall = Some(Wall::new(T::from_f64(-1.0)));
    let mut store = Buffers::<T>::new(Layout::for_params(&params, N, 0));
    let mut ws = store.workspace().with_parallel(par);
    for _ in 0..2 {
        step(&mut ps, &bonds, &params, &mut ws, &mut NoForce).unwrap();
    }
    bits::<T>(&ps.pos[..N])
}

#[test]
fn steps_above_the_wall_are_the_same_bits_on_any_thread_count() {
    const N: usize = BANDED_MIN + 40;
    let (one, one32) = (steps::<f64, N>(&Serial), steps::<f32, N>(&Serial));
    for t in [2, 3] {
        let pool = Threads::new(t).unwrap();
        assert_eq!(steps::<f64, N>(&pool), one, "{t} threads");
        assert_eq!(steps::<f32, N>(&pool), one32, "{t} threads, f32");
    }
}
