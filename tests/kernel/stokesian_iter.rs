//! The iterative Stokesian dynamics product against the dense mobility's product, on
//! random polydisperse clusters with near-contact pairs, in free space, in the box and
//! above the wall.
#![cfg(feature = "near")]

use hydrorattle::real::Real;
use hydrorattle::stokesian::iterative::{Solver, Storage, count_pairs, packed_product, sizes};
use hydrorattle::stokesian::{Far, NearField, SdError, mobility_in, storage};

/// A deterministic generator (64-bit LCG, top bits).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` spheres of radii 1 to 3, each placed at a gap from `min_gap` to 0.5 (log-uniform,
/// in mean radii) from a sphere placed before it, in a random direction, rejected where
/// it would come closer than `min_gap` to any other: a branched cluster full of
/// near-contact pairs, some spheres in several. Returns positions and radii.
pub fn cluster(n: usize, min_gap: f64, seed: u64) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut g = Lcg(seed);
    let (mut pos, mut rad) = (vec![[0.0; 3]], vec![1.0 + 2.0 * g.next()]);
    while pos.len() < n {
        let a = 1.0 + 2.0 * g.next();
        let k = (g.next() * pos.len() as f64) as usize;
        let gap = min_gap * (0.5 / min_gap).powf(g.next());
        let (z, phi) = (2.0 * g.next() - 1.0, 2.0 * std::f64::consts::PI * g.next());
        let s = (1.0 - z * z).sqrt();
        let d = (a + rad[k]) * 0.5 * (2.0 + gap);
        let p = [0, 1, 2].map(|c| pos[k][c] + d * [s * phi.cos(), s * phi.sin(), z][c]);
        let clear = pos.iter().zip(&rad).all(|(q, &b)| {
            let r: f64 = (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt();
            r >= (a + b) * 0.5 * (2.0 + min_gap * 0.999)
        });
        if clear {
            pos.push(p);
            rad.push(a);
        }
    }
    (pos, rad)
}

/// The iterative and the dense products of the same forces and torques, and the
/// iterations, in `far` (viscosity 1).
fn both<T: Real>(
    far: Far<'_, T>,
    pos: &[[f64; 3]],
    rad: &[f64],
    tol: f64,
    max_iter: u32,
) -> Result<(Vec<f64>, Vec<f64>, u32), SdError> {
    let n = pos.len();
    let p: Vec<T::V3> = pos.iter().map(|&x| T::v3_from(x)).collect();
    let r: Vec<T> = rad.iter().map(|&x| T::from_f64(x)).collect();
    let near = NearField::default();
    let mut g = Lcg(7);
    let f: Vec<T::V3> = (0..2 * n)
        .map(|_| T::v3_from([0, 1, 2].map(|_| 2.0 * g.next() - 1.0)))
        .collect();
    let (nb, nd) = storage(n);
    let mut packed = vec![T::M3_ZERO; nb];
    let mut dense = vec![T::ZERO; nd];
    mobility_in(T::ONE, far, &p, &r, near, &mut packed, &mut dense)?;
    let m = 6 * n;
    let fx: Vec<f64> = f
        .iter()
        .flat_map(|&v| T::xyz(v).map(|x| x.to_f64()))
        .collect();
    let want: Vec<f64> = (0..m)
        .map(|i| (0..m).map(|j| dense[i * m + j].to_f64() * fx[j]).sum())
        .collect();
    // The far field's product from its assembled grand mobility.
    far.assemble_grand(T::ONE, &p, &r, &mut packed)?;
    let mut cells = vec![0; 3 * n + 1];
    let np = count_pairs(far, &p, &r, near, &mut cells)?;
    let (npair, nreal, nfield, _) = sizes(n, np);
    let mut pairs = vec![[0; 2]; npair];
    let mut reals = vec![T::ZERO; nreal];
    let mut field = vec![T::V3_ZERO; nfield];
    let store = Storage {
        pairs: &mut pairs,
        reals: &mut reals,
        field: &mut field,
        cells: &mut cells,
    };
    let mut solver = Solver::new(T::ONE, far, &p, &r, near, store)?;
    let mut u = vec![T::V3_ZERO; 2 * n];
    let mut product = |x: &[T::V3], y: &mut [T::V3]| {
        packed_product::<T>(&packed, n, x, y);
        Ok(())
    };
    let rep = solver.product(&mut product, &f, &mut u, T::from_f64(tol), max_iter)?;
    let got: Vec<f64> = u
        .iter()
        .flat_map(|&v| T::xyz(v).map(|x| x.to_f64()))
        .collect();
    Ok((got, want, rep.iterations))
}

/// Largest difference relative to the largest entry of `want`.
fn rel(got: &[f64], want: &[f64]) -> f64 {
    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    got.iter()
        .zip(want)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale
}

#[test]
fn the_iterative_product_is_the_dense_one_in_free_space() {
    for (n, gap, seed, tol) in [
        (50, 1e-3, 1, 1e-8),
        (100, 1e-2, 2, 1e-6),
        (150, 1e-3, 3, 1e-4),
    ] {
        let (pos, rad) = cluster(n, gap, seed);
        let (got, want, it) = both::<f64>(Far::FREE, &pos, &rad, tol, 500).unwrap();
        let e = rel(&got, &want);
        println!("n = {n}, smallest gap {gap}, tol {tol:e}: {it} iterations, error {e:.2e}");
        assert!(e < 10.0 * tol.max(1e-12), "n = {n}: error {e}");
    }
}

#[test]
fn the_iterative_product_is_the_dense_one_in_f32() {
    let (pos, rad) = cluster(60, 1e-2, 4);
    let (got, want, it) = both::<f32>(Far::FREE, &pos, &rad, 1e-4, 500).unwrap();
    let e = rel(&got, &want);
    println!("f32: {it} iterations, error {e:.2e}");
    assert!(e < 1e-2, "error {e}");
}

#[cfg(feature = "periodic")]
#[test]
fn the_iterative_product_is_the_dense_one_in_the_box() {
    use hydrorattle::cell::Periodic;
    use hydrorattle::mobility::periodic::Ewald;
    let (pos, rad) = cluster(80, 1e-3, 5);
    // A box around the cluster's middle, small enough that pairs meet across its faces.
    let l = 24.0;
    let cell = Periodic::new([l; 3]).unwrap();
    let ew = Ewald::new(cell, 3.0).unwrap();
    let (got, want, it) = both::<f64>(Far::periodic(&ew), &pos, &rad, 1e-8, 500).unwrap();
    let e = rel(&got, &want);
    println!("box: {it} iterations, error {e:.2e}");
    assert!(e < 1e-7, "error {e}");
}

#[test]
fn iterations_against_the_smallest_gap() {
    // The same cluster shape with its gaps scaled down: the block-Jacobi over pairs
    // takes the lubrication's stiffness out, so the count stays bounded.
    let mut counts = Vec::new();
    for gap in [1e-1, 1e-2, 1e-3, 1e-4] {
        let (pos, rad) = cluster(60, gap, 6);
        let (got, want, it) = both::<f64>(Far::FREE, &pos, &rad, 1e-8, 500).unwrap();
        println!(
            "smallest gap {gap:e}: {it} iterations, error {:.2e}",
            rel(&got, &want)
        );
        counts.push(it);
    }
    assert!(counts.iter().all(|&k| k < 150), "{counts:?}");
}

#[test]
fn the_same_bits_on_rerun_and_errors_are_typed() {
    let (pos, rad) = cluster(70, 1e-3, 8);
    let a = both::<f64>(Far::FREE, &pos, &rad, 1e-8, 500).unwrap().0;
    let b = both::<f64>(Far::FREE, &pos, &rad, 1e-8, 500).unwrap().0;
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    let r = both::<f64>(Far::FREE, &pos, &rad, 1e-12, 2);
    assert!(
        matches!(r, Err(SdError::NotConverged { iterations: 2, .. })),
        "{r:?}"
    );
}

/// Above the wall (Blake's images in the far field, each sphere inside the wall's
/// cutoff one more entry of the near field), the lowest sphere at a gap of 1e-3 to 0.1
/// radii: the product is the dense mobility's (`mobility_in` with the same wall
/// corrections) within ten times the tolerance, as in free space; and refused before
/// (`SdError::Params`), so this fails on a product without the wall.
#[test]
fn the_iterative_product_is_the_dense_one_above_the_wall() {
    for (n, gap, seed, tol) in [
        (1, 0.1, 9, 1e-8),
        (40, 1e-3, 10, 1e-8),
        (80, 1e-2, 11, 1e-6),
    ] {
        let (pos, rad) = cluster(n, 1e-2, seed);
        let floor = pos
            .iter()
            .zip(&rad)
            .map(|(p, a)| p[2] - a)
            .fold(f64::INFINITY, f64::min);
        let wall = Far::above(floor - gap);
        let (got, want, it) = both::<f64>(wall, &pos, &rad, tol, 500).unwrap();
        let e = rel(&got, &want);
        println!("wall, n = {n}, gap {gap}, tol {tol:e}: {it} iterations, error {e:.2e}");
        assert!(e < 10.0 * tol, "n = {n}: error {e}");
    }
    let (pos, rad) = cluster(30, 1e-2, 12);
    let floor = pos
        .iter()
        .zip(&rad)
        .map(|(p, a)| p[2] - a)
        .fold(f64::INFINITY, f64::min);
    let (got, want, it) =
        both::<f32>(Far::above(floor as f32 - 0.01), &pos, &rad, 1e-4, 500).unwrap();
    let e = rel(&got, &want);
    println!("wall, f32: {it} iterations, error {e:.2e}");
    assert!(e < 1e-2, "f32: error {e}");
}
