//! The compact `f32` copy of a periodic box's stored mobility
//! (`Params::compact_products` with Ewald sums): every product read from the copy agrees
//! with the `f64` product of the stored Ewald blocks to `f32` rounding (`~1e-7`
//! relative; the bound 1e-6). The `f64` products are the reference: the copy's path
//! computes none of them. The free-space mobility of the same spheres gives products
//! off by 0.46 to 15 times the box's (the box removes the mean flow), so a copy of the
//! wrong blocks fails by far. The copy is packed by `reduced::copy_apply`, whose packer
//! is the one the box's assembly pass calls row by row; that pass itself (the blocks
//! and first product unchanged by packing) is checked in `geometry::periodic::held`'s unit
//! test, and whole compact steps in a box in `parallel/tests/parallel/compact.rs`.
//!
//! 512 spheres (`BANDED_MIN`: sixteen bands, two column tiles of the copy) on a
//! jittered 8^3 lattice of spacing 3 filling a box of edge 24 (radii 0.8 to 1, volume
//! fraction 0.12: images at every distance).

use glam::DVec3;
use hydrorattle::Real;
use hydrorattle::cell::Periodic;
use hydrorattle::linalg::{Sym, tri};
use hydrorattle::mobility::Hydro;
use hydrorattle::mobility::periodic::{self, Ewald};
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Serial, band_scratch};

/// Largest entry of `a - b` over the largest entry of `b`.
fn gap(a: &[DVec3], b: &[DVec3]) -> f64 {
    let top = |v: &[DVec3]| v.iter().fold(0.0, |m: f64, x| m.max(x.abs().max_element()));
    let d: Vec<DVec3> = a.iter().zip(b).map(|(x, y)| *x - *y).collect();
    top(&d) / top(b)
}

#[test]
fn a_boxs_compact_copy_gives_its_products_to_f32_rounding() {
    let (n, l) = (512, 24.0);
    let pos: Vec<DVec3> = (0..n)
        .map(|k| {
            let site = DVec3::new((k % 8) as f64, ((k / 8) % 8) as f64, (k / 64) as f64);
            let t = k as f64;
            let jitter = DVec3::new((1.3 * t).sin(), (0.7 * t).cos(), (2.1 * t).sin());
            3.0 * site + 1.5 + 0.2 * jitter
        })
        .collect();
    let radius: Vec<f64> = (0..n).map(|i| 0.8 + 0.05 * (i % 5) as f64).collect();
    let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0).unwrap();
    let mut bands = vec![DVec3::ZERO; band_scratch(n)];
    let mut boxed: Vec<Sym<f64>> = vec![[0.0; 6]; tri(n)];
    periodic::assemble(&Serial, &ew, 1.0, &pos, &radius, &mut boxed).unwrap();
    let mut free: Vec<Sym<f64>> = vec![[0.0; 6]; tri(n)];
    parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut free).unwrap();
    let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
    let mut worst: f64 = 0.0;
    for q in 0..4 {
        let x: Vec<DVec3> = (0..n)
            .map(|i| {
                let t = (i * (q + 1)) as f64;
                DVec3::new((0.37 * t).sin(), (0.11 * t).cos(), 1.0 - q as f64 * 0.5)
            })
            .collect();
        let (mut exact, mut compact, mut open) = (
            vec![DVec3::ZERO; n],
            vec![DVec3::ZERO; n],
            vec![DVec3::ZERO; n],
        );
        parallel::product::<f64>(&Serial, &boxed, n, &x, &mut exact, &mut bands);
        reduced::copy_apply::<f64>(&Serial, &boxed, n, &mut copy, &x, &mut compact, &mut bands);
        parallel::product::<f64>(&Serial, &free, n, &x, &mut open, &mut bands);
        let (g, wrong) = (gap(&compact, &exact), gap(&open, &exact));
        assert!(g < 1e-6, "vector {q}: compact vs f64 {g:e}");
        assert!(wrong > 0.1, "vector {q}: free space vs box only {wrong:e}");
        worst = worst.max(g);
    }
    eprintln!("box, N = {n}: compact vs f64 products, largest relative gap {worst:.2e}");
}
