//! The periodic (Ewald) mobility on a thread pool gives the bits of one thread: the
//! banded assembly ([`periodic::assemble`]) the blocks of the serial one, the
//! matrix-free product ([`periodic::free_product`]: the real-space half in the bands
//! of the stored product, the wave-space half on the calling thread) the same bits on
//! 1 to 4 threads, those of the one-band [`periodic::tt_product`] below
//! [`BANDED_MIN`](hydrorattle::parallel::BANDED_MIN) rows, and above it the product of
//! the assembled matrix to rounding; the first nested pair is the same error on any
//! thread count.

use hydrorattle::glam::{DMat3, DVec3};
use hydrorattle::mobility::periodic::{self, Ewald, XI_BALANCE};
use hydrorattle::parallel::{Parallel, Serial, band_scratch};
use hydrorattle::{ParticleError, Periodic, PeriodicError, linalg};
use hydrorattle_parallel::Threads;

use crate::fuzz::Rng;

/// `n` spheres of radii 0.8 to 1.2 at volume fraction about 0.05, forces, and the Ewald
/// sums of their box at a tolerance of 1e-6 (cheaper than the default's near-epsilon
/// one; the arithmetic's order, which the bits test, is the same).
fn spheres(n: usize) -> (Ewald<f64>, Vec<DVec3>, Vec<f64>, Vec<DVec3>) {
    let l = (n as f64 * 4.0 / 3.0 * std::f64::consts::PI / 0.05).cbrt();
    let mut s = Rng(n as u64);
    let mut v = |scale: f64, shift: f64| {
        let (a, b, c) = (s.unit(), s.unit(), s.unit());
        DVec3::new(a, b, c) * scale - DVec3::splat(shift)
    };
    let pos: Vec<DVec3> = (0..n).map(|_| v(l, 0.0)).collect();
    let f: Vec<DVec3> = (0..n).map(|_| v(1.0, 0.5)).collect();
    let radius: Vec<f64> = (0..n).map(|k| 0.8 + 0.4 * (k % 7) as f64 / 6.0).collect();
    let cell = Periodic::new([l; 3]).unwrap();
    let ew = Ewald::with_xi(cell, 1.25, XI_BALANCE / l, 1e-6).unwrap();
    (ew, pos, radius, f)
}

/// The banded matrix-free product through `par`.
fn free(
    ew: &Ewald<f64>,
    pos: &[DVec3],
    radius: &[f64],
    f: &[DVec3],
    par: &dyn Parallel,
) -> Result<Vec<DVec3>, PeriodicError> {
    let n = pos.len();
    let (mut y, mut z) = (vec![DVec3::ZERO; n], vec![DVec3::ONE; band_scratch(n)]);
    periodic::free_product(par, ew, 0.7, pos, radius, f, &mut y, &mut z)?;
    Ok(y)
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|u| u.to_array().map(f64::to_bits)).collect()
}

#[test]
fn ewald_products_and_assembly_give_the_same_bits_on_any_thread_count() {
    let pools: Vec<Threads> = (1..=4).map(|t| Threads::new(t).unwrap()).collect();
    // One band (and the serial product's bits), then sixteen.
    for n in [40, 560] {
        let (ew, pos, radius, f) = spheres(n);
        let one = free(&ew, &pos, &radius, &f, &Serial).unwrap();
        for pool in &pools {
            let many = free(&ew, &pos, &radius, &f, pool).unwrap();
            assert!(
                bits(&many) == bits(&one),
                "n {n}, {} threads",
                pool.threads()
            );
        }
        let mut serial = vec![DVec3::ZERO; n];
        periodic::tt_product(&ew, 0.7, &pos, &radius, &f, &mut serial).unwrap();
        // The assembled matrix: the banded assembly's blocks are the serial one's.
        let mut mu = vec![DMat3::ZERO; n * (n + 1) / 2];
        periodic::assemble_tt(&ew, 0.7, &pos, &radius, &mut mu).unwrap();
        for pool in &pools {
            let mut banded = vec![DMat3::NAN; n * (n + 1) / 2];
            periodic::assemble(pool, &ew, 0.7, &pos, &radius, &mut banded).unwrap();
            let same = mu.iter().zip(&banded).all(|(a, b)| {
                a.to_cols_array().map(f64::to_bits) == b.to_cols_array().map(f64::to_bits)
            });
            assert!(same, "n {n}, {} threads: assembly", pool.threads());
        }
        let mut dense = vec![DVec3::ZERO; n];
        linalg::sym_matvec::<f64>(&mu, n, &f, &mut dense);
        let scale = dense
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
        let worst = |a: &[DVec3]| {
            a.iter()
                .zip(&dense)
                .fold(0.0f64, |m, (u, v)| m.max((*u - *v).abs().max_element()))
                / scale
        };
        if n < 512 {
            assert!(bits(&serial) == bits(&one), "n {n}: the one-band product");
        }
        assert!(worst(&one) < 1e-12, "n {n}: {:e}", worst(&one));
        assert!(worst(&serial) < 1e-12, "n {n}: {:e}", worst(&serial));
    }
}

#[test]
fn the_first_nested_pair_is_the_error_on_any_thread_count() {
    let (ew, mut pos, radius, f) = spheres(560);
    // Two coincident pairs in different bands: the one in the earlier row is reported.
    pos[500] = pos[20];
    pos[300] = pos[10];
    let nested = PeriodicError::Particle(ParticleError::Nested { i: 10, j: 300 });
    let mut serial = vec![DVec3::ZERO; 560];
    let e = periodic::tt_product(&ew, 0.7, &pos, &radius, &f, &mut serial);
    assert_eq!(e, Err(nested));
    for t in 1..=3 {
        let pool = Threads::new(t).unwrap();
        assert_eq!(
            free(&ew, &pos, &radius, &f, &pool),
            Err(nested),
            "{t} threads"
        );
        let mut mu = vec![DMat3::ZERO; 560 * 561 / 2];
        let e = periodic::assemble(&pool, &ew, 0.7, &pos, &radius, &mut mu);
        assert_eq!(e, Err(nested), "{t} threads: assembly");
    }
}
