//! The wall's mobility (issue 21) in bands on a thread pool: the bits of one thread for
//! the assembly, the banded product and whole overdamped steps above the wall.

use hydrorattle::glam::DVec3;
use hydrorattle::mobility::wall;
use hydrorattle::parallel::{self, BANDED_MIN, Parallel, Serial, band_scratch, bands};
use hydrorattle::{Hydro, Layout, NoForce, Params, Real, State, Wall, step_slices};
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

/// Two overdamped steps of the grid settling towards the wall.
fn steps<T: Real>(n: usize, par: &dyn Parallel) -> Vec<u64> {
    let (p, radius) = grid(n);
    let mut pos: Vec<T::V3> = p.iter().map(|&x| T::v3_from(x)).collect();
    let radius: Vec<T> = radius.iter().map(|&a| T::from_f64(a)).collect();
    let mut params = Params::<T>::new(T::from_f64(0.01));
    params.wall = Some(Wall::new(T::from_f64(-1.0)));
    let mut store = Buffers::<T>::new(Layout::for_params(&params, n, 0));
    let mut ws = store.workspace().with_parallel(par);
    let (mut vel, mut omega) = (vec![T::V3_ZERO; n], vec![T::V3_ZERO; n]);
    let density = vec![T::from_f64(2.0); n];
    let mut time = T::ZERO;
    for _ in 0..2 {
        let state = State {
            pos: &mut pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time: &mut time,
            noise: None,
        };
        step_slices(state, &[], &params, &mut ws, &mut NoForce).unwrap();
    }
    bits::<T>(&pos)
}

#[test]
fn steps_above_the_wall_are_the_same_bits_on_any_thread_count() {
    let n = BANDED_MIN + 40;
    let (one, one32) = (steps::<f64>(n, &Serial), steps::<f32>(n, &Serial));
    for t in [2, 3] {
        let pool = Threads::new(t).unwrap();
        assert_eq!(steps::<f64>(n, &pool), one, "{t} threads");
        assert_eq!(steps::<f32>(n, &pool), one32, "{t} threads, f32");
    }
}
