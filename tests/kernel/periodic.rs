//! The periodic box's Ewald-summed RPY mobility (`mobility::periodic`), against values
//! the code under test did not produce: Hasimoto's expansion for a lone sphere in a
//! cubic box, the free-space RPY as the box grows, and its own independence of the
//! splitting parameter; positive definiteness as property tests, in f32 and f64.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::boxes::{config, to_t};
use common::fuzz::Rng;
use common::loglog_slope;
use hydrorattle::Real;
use hydrorattle::error::ParticleError;
use hydrorattle::linalg::{cholesky, sym_get, sym_matvec, tri};
use hydrorattle::mobility::periodic::{
    Ewald, Periodic, PeriodicError, add_spin, assemble_grand, assemble_tt, pair_rot, pair_tt,
    self_rr, self_tt, tt_product,
};
use hydrorattle::mobility::{self, Hydro};
use proptest::prelude::*;

/// Hasimoto's constant for the simple cubic lattice (Hasimoto, J. Fluid Mech. 5, 317,
/// 1959, to the digits of the later literature): `1.7601 (4 pi / 3)^{1/3}` to 13 digits.
const HASIMOTO: f64 = 2.837_297_479_480_6;

type M = [[f64; 3]; 3];

fn m64<T: Real>(m: T::M3) -> M {
    let mut o = [[0.0; 3]; 3];
    for r in 0..3 {
        for c in 0..3 {
            o[r][c] = T::m3_get(m, r, c).to_f64();
        }
    }
    o
}

fn max_abs(m: &M) -> f64 {
    m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

fn max_diff(a: &M, b: &M) -> f64 {
    let mut d = 0.0f64;
    for r in 0..3 {
        for c in 0..3 {
            d = d.max((a[r][c] - b[r][c]).abs());
        }
    }
    d
}

fn assemble<T: Real>(ew: &Ewald<T>, pos: &[T::V3], rad: &[T]) -> Vec<T::M3> {
    let mut out = vec![T::M3_ZERO; tri(pos.len())];
    assemble_tt(ew, T::ONE, pos, rad, &mut out).unwrap();
    out
}

/// The `2n x 2n` grand mobility of the box (`eta = 1`), packed lower triangle.
fn grand<T: Real>(ew: &Ewald<T>, pos: &[T::V3], rad: &[T]) -> Vec<T::M3> {
    let mut out = vec![T::M3_ZERO; tri(2 * pos.len())];
    assemble_grand(ew, T::ONE, pos, rad, &mut out).unwrap();
    out
}

/// The rule's `xi`, and the three splitting parameters of the independence checks.
fn xis(size: [f64; 3], a_max: f64) -> [f64; 3] {
    let xi = Ewald::new(Periodic::new(size).unwrap(), a_max)
        .unwrap()
        .xi();
    [0.6 * xi, xi, 1.7 * xi]
}

#[test]
fn hasimoto_lone_sphere() {
    let mut rem = vec![];
    for l in [5.0, 10.0, 20.0, 50.0, 100.0] {
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0f64).unwrap();
        let m = m64::<f64>(self_tt(&ew, 1.0, 1.0));
        let x = 1.0 / l;
        let want = 1.0 - HASIMOTO * x + 4.0 / 3.0 * core::f64::consts::PI * x * x * x;
        let got = m[0][0] * 6.0 * core::f64::consts::PI;
        let r = got - want;
        println!(
            "L/a = {l:>5}: mu 6 pi eta a = {got:.16}, remainder {r:+.3e}, (a/L)^6 = {:.1e}",
            x.powi(6)
        );
        // Isotropic (cubic symmetry) and the remainder far below (a/L)^6: the RPY tensor's
        // expansion ends at (a/L)^3 (its sphere factor is exact at a/L < 1/2), so what is
        // left is rounding plus the constant's last digit (1e-13 a/L).
        let iso = [
            [m[0][0], 0.0, 0.0],
            [0.0, m[0][0], 0.0],
            [0.0, 0.0, m[0][0]],
        ];
        assert!(max_diff(&m, &iso) < 1e-16, "L/a = {l}: not isotropic {m:?}");
        assert!(
            r.abs() < 1e-3 * x.powi(6) + 2e-15,
            "L/a = {l}: remainder {r:e}"
        );
        rem.push(r.abs());
    }
    // f32: to its own precision.
    for l in [5.0f32, 20.0, 100.0] {
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0f32).unwrap();
        let got = m64::<f32>(self_tt(&ew, 1.0, 1.0))[0][0] * 6.0 * core::f64::consts::PI;
        let x = 1.0 / l as f64;
        let want = 1.0 - HASIMOTO * x + 4.0 / 3.0 * core::f64::consts::PI * x * x * x;
        assert!((got - want).abs() < 2e-6, "f32 L/a = {l}: {got} vs {want}");
    }
    println!("remainders {rem:?}");
}

/// Every block of two assemblies, relative to the largest entry.
fn rel_diff(a: &[hydrorattle::glam::DMat3], b: &[hydrorattle::glam::DMat3]) -> f64 {
    let scale = a
        .iter()
        .map(|m| max_abs(&m64::<f64>(*m)))
        .fold(0.0, f64::max);
    a.iter()
        .zip(b)
        .map(|(x, y)| max_diff(&m64::<f64>(*x), &m64::<f64>(*y)))
        .fold(0.0, f64::max)
        / scale
}

/// An assembly of the box's mobility (`assemble` or `grand`).
type Build = fn(&Ewald<f64>, &[hydrorattle::glam::DVec3], &[f64]) -> Vec<hydrorattle::glam::DMat3>;

/// The largest relative difference of the matrix `build` assembles at the three
/// splitting parameters of [`xis`] from the one at the rule's.
fn across_xi(
    size: [f64; 3],
    a_hi: f64,
    pos: &[hydrorattle::glam::DVec3],
    rad: &[f64],
    build: Build,
) -> f64 {
    let cell = Periodic::new(size).unwrap();
    let mats: Vec<_> = xis(size, a_hi)
        .iter()
        .map(|&xi| {
            build(
                &Ewald::with_xi(cell, a_hi, xi, f64::EPSILON / 8.0).unwrap(),
                pos,
                rad,
            )
        })
        .collect();
    rel_diff(&mats[0], &mats[1]).max(rel_diff(&mats[2], &mats[1]))
}

#[test]
fn independent_of_splitting_parameter() {
    let (mut worst, mut worst_rot) = (0.0f64, 0.0f64);
    for (size, a_hi) in [
        ([10.0; 3], 2.0),
        ([7.0, 11.0, 16.0], 2.0),
        ([6.0, 6.0, 6.0], 2.9),
    ] {
        for seed in 0..4u64 {
            let (p, r) = config(10, seed, size, a_hi, seed % 2 == 1);
            let (pos, rad) = to_t::<f64>(&p, &r);
            let d = across_xi(size, a_hi, &pos, &rad, assemble::<f64>);
            worst = worst.max(d);
            assert!(
                d < 1e-13,
                "box {size:?} seed {seed}: relative difference {d:e}"
            );
            // The grand matrix, rotation blocks included.
            let dg = across_xi(size, a_hi, &pos, &rad, grand::<f64>);
            worst_rot = worst_rot.max(dg);
            assert!(dg < 1e-13, "box {size:?} seed {seed}: grand {dg:e}");
        }
    }
    println!("largest relative difference across xi: {worst:.2e} (grand {worst_rot:.2e})");
}

#[test]
fn large_box_tends_to_free_space() {
    let (ai, aj, r) = (1.0, 0.6, [1.1, 0.7, -0.4]);
    let free = m64::<f64>(
        mobility::pair_tt(Hydro::Rpy, 1.0, ai, aj, hydrorattle::glam::DVec3::from(r)).unwrap(),
    );
    let (mut ls, mut ds) = (vec![], vec![]);
    for l in [10.0, 20.0, 40.0, 80.0, 160.0] {
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), ai).unwrap();
        let m = m64::<f64>(pair_tt(&ew, 1.0, ai, aj, r.into()).unwrap());
        ls.push(l);
        ds.push(max_diff(&m, &free));
    }
    let slope = loglog_slope(&ls[1..], &ds[1..]);
    println!("|M_L - M_free| {ds:?}, slope {slope:.4}");
    assert!((slope + 1.0).abs() < 0.02, "slope {slope}");
    // The 1/L coefficient: a unit force on the pair is screened like the lone sphere's
    // Hasimoto term, -2.837297 / (6 pi eta L) on the diagonal.
    let lead = ds[4] * ls[4];
    let want = HASIMOTO / (6.0 * core::f64::consts::PI);
    assert!(
        (lead - want).abs() < 2e-3 * want,
        "L |dM| = {lead}, want {want}"
    );
}

/// Cholesky of the assembled `mu_tt` (or, with `rotation`, of the `6N` grand matrix).
fn positive_definite<T: Real>(n: usize, seed: u64, size: [f64; 3], overlap: bool, rotation: bool) {
    let (p, r) = config(n, seed, size, 2.0, overlap);
    let (pos, rad) = to_t::<T>(&p, &r);
    let ew = Ewald::new(
        Periodic::new(size.map(T::from_f64)).unwrap(),
        T::from_f64(2.0),
    )
    .unwrap();
    let (mut fac, m) = match rotation {
        true => (grand(&ew, &pos, &rad), 2 * pos.len()),
        false => (assemble(&ew, &pos, &rad), pos.len()),
    };
    let res = cholesky::<T>(&mut fac, m);
    assert!(
        res.is_ok(),
        "n = {} seed {seed} box {size:?} overlap {overlap} rotation {rotation}: {res:?}",
        pos.len()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn positive_definite_grand_f64(n in 1usize..=10, seed in any::<u64>(), lx in 4.5f64..12.0, ly in 4.5f64..12.0, lz in 4.5f64..12.0, overlap in any::<bool>()) {
        positive_definite::<f64>(n, seed, [lx, ly, lz], overlap, true);
    }
    #[test]
    fn positive_definite_grand_f32(n in 1usize..=10, seed in any::<u64>(), lx in 4.5f64..12.0, ly in 4.5f64..12.0, lz in 4.5f64..12.0, overlap in any::<bool>()) {
        positive_definite::<f32>(n, seed, [lx, ly, lz], overlap, true);
    }
    #[test]
    fn positive_definite_f64(n in 1usize..=10, seed in any::<u64>(), lx in 4.5f64..12.0, ly in 4.5f64..12.0, lz in 4.5f64..12.0, overlap in any::<bool>()) {
        positive_definite::<f64>(n, seed, [lx, ly, lz], overlap, false);
    }
    #[test]
    fn positive_definite_f32(n in 1usize..=10, seed in any::<u64>(), lx in 4.5f64..12.0, ly in 4.5f64..12.0, lz in 4.5f64..12.0, overlap in any::<bool>()) {
        positive_definite::<f32>(n, seed, [lx, ly, lz], overlap, false);
    }
}

#[test]
fn symmetry_and_translation() {
    // L = 8 and positions on a 1/1024 grid: shifts by box vectors are exact.
    let size = [8.0, 8.0, 8.0];
    let (p, r) = config(8, 7, size, 1.5, true);
    let grid = |v: f64| (v * 1024.0).round() / 1024.0;
    let p: Vec<[f64; 3]> = p.iter().map(|q| q.map(grid)).collect();
    let (pos, rad) = to_t::<f64>(&p, &r);
    let ew = Ewald::new(Periodic::new(size).unwrap(), 1.5).unwrap();
    let m = assemble(&ew, &pos, &rad);
    let n = pos.len();
    for i in 0..n {
        for j in 0..n {
            let b = m64::<f64>(sym_get::<f64>(&m, i, j));
            let t = m64::<f64>(pair_or_self(&ew, &pos, &rad, j, i));
            let bt = [0, 1, 2].map(|r| [0, 1, 2].map(|c| t[c][r]));
            assert!(
                max_diff(&b, &bt) <= 1e-15 * max_abs(&b).max(1e-3),
                "M_{i}{j} vs M_{j}{i}^T"
            );
            if i != j {
                // Each block itself is exactly symmetric.
                assert_eq!(b, [0, 1, 2].map(|r| [0, 1, 2].map(|c| b[c][r])));
            }
        }
    }
    // Every sphere moved by its own box vector: the same bits.
    let shifted: Vec<_> = p
        .iter()
        .enumerate()
        .map(|(i, q)| {
            [
                q[0] + 8.0 * (i % 3) as f64,
                q[1] - 8.0 * (i % 2) as f64,
                q[2] + 16.0,
            ]
        })
        .collect();
    let (pos2, _) = to_t::<f64>(&shifted, &r);
    assert_eq!(assemble(&ew, &pos2, &rad), m);
    // A common shift that is not a box vector: the same to rounding.
    let moved: Vec<_> = p
        .iter()
        .map(|q| [q[0] + 0.37, q[1] - 5.1, q[2] + 2.9])
        .collect();
    let (pos3, _) = to_t::<f64>(&moved, &r);
    assert!(rel_diff(&assemble(&ew, &pos3, &rad), &m) < 1e-14);
}

fn pair_or_self<T: Real>(ew: &Ewald<T>, pos: &[T::V3], rad: &[T], i: usize, j: usize) -> T::M3 {
    if i == j {
        self_tt(ew, T::ONE, rad[i])
    } else {
        pair_tt(ew, T::ONE, rad[i], rad[j], pos[i] - pos[j]).unwrap()
    }
}

#[test]
fn product_matches_assembly() {
    let size = [9.0, 10.0, 12.0];
    for overlap in [false, true] {
        let (p, r) = config(12, 3, size, 2.0, overlap);
        let (pos, rad) = to_t::<f64>(&p, &r);
        let ew = Ewald::new(Periodic::new(size).unwrap(), 2.0).unwrap();
        let m = assemble(&ew, &pos, &rad);
        let mut rng = Rng(11);
        let x: Vec<_> = pos
            .iter()
            .map(|_| {
                hydrorattle::glam::DVec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
            })
            .collect();
        let (mut y1, mut y2) = (
            vec![Default::default(); pos.len()],
            vec![Default::default(); pos.len()],
        );
        sym_matvec::<f64>(&m, pos.len(), &x, &mut y1);
        tt_product(&ew, 1.0, &pos, &rad, &x, &mut y2).unwrap();
        let scale = y1
            .iter()
            .map(|v: &hydrorattle::glam::DVec3| v.abs().max_element())
            .fold(0.0, f64::max);
        let d = y1
            .iter()
            .zip(&y2)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f64::max);
        assert!(
            d < 1e-13 * scale,
            "product vs assembly: {d:e} (scale {scale:e})"
        );
    }
}

#[test]
fn f32_agrees_with_f64() {
    let size = [8.0, 9.0, 10.0];
    let (p, r) = config(8, 5, size, 2.0, true);
    let m64s = {
        let (pos, rad) = to_t::<f64>(&p, &r);
        assemble(
            &Ewald::new(Periodic::new(size).unwrap(), 2.0).unwrap(),
            &pos,
            &rad,
        )
    };
    let (pos, rad) = to_t::<f32>(&p, &r);
    let ew = Ewald::new(Periodic::new(size.map(|v| v as f32)).unwrap(), 2.0f32).unwrap();
    let m32 = assemble(&ew, &pos, &rad);
    let scale = m64s
        .iter()
        .map(|m| max_abs(&m64::<f64>(*m)))
        .fold(0.0, f64::max);
    let d = m64s
        .iter()
        .zip(&m32)
        .map(|(a, b)| max_diff(&m64::<f64>(*a), &m64::<f32>(*b)))
        .fold(0.0, f64::max);
    assert!(d < 2e-6 * scale, "f32 vs f64: {:e}", d / scale);
}

#[test]
fn rejects_bad_input() {
    for (size, axis) in [
        ([0.0, 1.0, 1.0], 0),
        ([1.0, -1.0, 1.0], 1),
        ([1.0, 1.0, f64::NAN], 2),
        ([1.0, f64::INFINITY, 1.0], 1),
    ] {
        assert_eq!(Periodic::new(size), Err(PeriodicError::BadEdge { axis }));
    }
    let cell = Periodic::new([10.0, 10.0, 10.0]).unwrap();
    assert_eq!(
        Ewald::new(cell, 5.0).err(),
        Some(PeriodicError::SphereTooLarge)
    );
    assert_eq!(
        Ewald::new(cell, 0.0).err(),
        Some(PeriodicError::BadParameter("largest radius"))
    );
    assert_eq!(
        Ewald::with_xi(cell, 1.0, -1.0, 1e-16).err(),
        Some(PeriodicError::BadParameter("xi"))
    );
    assert_eq!(
        Ewald::with_xi(cell, 1.0, 0.3, 0.0).err(),
        Some(PeriodicError::BadParameter("tolerance"))
    );
    let thin = Periodic::new([1.0, 1.0, 1000.0]).unwrap();
    assert_eq!(
        Ewald::new(thin, 0.1).err(),
        Some(PeriodicError::TooElongated)
    );
    let ew = Ewald::new(cell, 1.0).unwrap();
    let mut out = vec![hydrorattle::glam::DMat3::ZERO; 3];
    let p = |x: f64| hydrorattle::glam::DVec3::new(x, 1.0, 1.0);
    let e = assemble_tt(&ew, 1.0, &[p(1.0), p(3.0)], &[1.0, 1.5], &mut out);
    assert_eq!(e, Err(PeriodicError::Radius { particle: 1 }));
    let e = assemble_tt(&ew, 1.0, &[p(1.0), p(f64::NAN)], &[1.0, 1.0], &mut out);
    assert_eq!(
        e,
        Err(PeriodicError::Particle(ParticleError::NonFinite {
            particle: 1
        }))
    );
    // Nested through the box: 9.8 apart is 0.2 apart across the boundary.
    let e = assemble_tt(&ew, 1.0, &[p(0.1), p(9.9)], &[1.0, 0.5], &mut out);
    assert_eq!(
        e,
        Err(PeriodicError::Particle(ParticleError::Nested {
            i: 0,
            j: 1
        }))
    );
    let mut y = vec![hydrorattle::glam::DVec3::ZERO; 2];
    let e = tt_product(
        &ew,
        1.0,
        &[p(0.1), p(9.9)],
        &[1.0, 0.5],
        &[p(0.0), p(0.0)],
        &mut y,
    );
    assert_eq!(
        e,
        Err(PeriodicError::Particle(ParticleError::Nested {
            i: 0,
            j: 1
        }))
    );
}

/// Cost per pair block and per assembly (`cargo test --release --test kernel periodic:: -- --ignored --nocapture`).
#[test]
#[ignore]
fn timing() {
    for n in [100usize, 1000] {
        let side = (n as f64 * 4.0 / 3.0 * core::f64::consts::PI / 0.1).cbrt();
        let size = [side; 3];
        let (p, r) = config(n, 1, size, 1.0, false);
        let (pos, rad) = to_t::<f64>(&p, &r);
        let ew = Ewald::new(Periodic::new(size).unwrap(), 1.0).unwrap();
        let t = std::time::Instant::now();
        let m = assemble(&ew, &pos, &rad);
        let dt = t.elapsed().as_secs_f64();
        let x = vec![hydrorattle::glam::DVec3::ONE; n];
        let mut y = vec![hydrorattle::glam::DVec3::ZERO; n];
        let t = std::time::Instant::now();
        tt_product(&ew, 1.0, &pos, &rad, &x, &mut y).unwrap();
        let dp = t.elapsed().as_secs_f64();
        println!(
            "N = {n} (phi 0.1, L = {side:.1}): assembly {dt:.3} s ({:.2} us/pair), product {dp:.3} s, blocks {}",
            dt * 1e6 / (n * (n + 1) / 2) as f64,
            m.len()
        );
    }
}

/// A lone sphere's rotational mobility in a cubic box: `8 pi eta a^3 mu_rr =
/// 1 - (4 pi / 3)(a/L)^3` (the images lie beyond contact, where the RPY `rr` block is
/// the point dipole `-(I - 3 e e) / (16 pi eta r^3)`, whose sum over each cubic shell is
/// zero; what remains is the excluded mean `k = 0`, the direction average `(2/3) I / 4`
/// of `P(k) / 4`, over `eta V`: `1 - V_sphere / V_box`, the form of the finite-size
/// correction of rotational diffusion of Linke, Köfinger and Hummer, J. Phys. Chem.
/// Lett. 9, 2874, 2018).
#[test]
fn rotation_lone_sphere_cubic() {
    for l in [2.5, 5.0, 10.0, 20.0, 100.0] {
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.0).unwrap();
        let m = m64::<f64>(self_rr(&ew, 1.0, 1.0));
        let got = m[0][0] * 8.0 * core::f64::consts::PI;
        let want = 1.0 - 4.0 * core::f64::consts::PI / 3.0 / (l * l * l);
        let off = m[0][1].abs().max(m[0][2].abs()).max(m[1][2].abs());
        println!(
            "L/a = {l}: 8 pi eta a^3 mu_rr = {got:.16} (want {want:.16}, {:.1e})",
            got - want
        );
        assert!((got - want).abs() < 2e-14, "L {l}: {got} vs {want}");
        assert!((m[1][1] - m[0][0]).abs() < 1e-15 && (m[2][2] - m[0][0]).abs() < 1e-15);
        assert!(off < 1e-15, "off-diagonal {off:e}");
        // The rt self block is zero, and a pair's rt, rr agree with the grand matrix.
        let g = grand(&ew, &[[0.1, 0.2, 0.3].into()], &[1.0]);
        assert_eq!(max_abs(&m64::<f64>(g[tri(1)])), 0.0);
    }
}

/// The rotation blocks tend to free space's as the box grows, the difference falling
/// as `1/L^3` (the mean vorticity excluded with `k = 0` and the images' dipolar field).
#[test]
fn rotation_large_box_tends_to_free_space() {
    let (ai, aj, r) = (1.0, 0.6, [1.1, 0.7, -0.4]);
    let free =
        mobility::pair_blocks(Hydro::Rpy, 1.0, ai, aj, hydrorattle::glam::DVec3::from(r)).unwrap();
    let (mut ls, mut d) = (vec![], [vec![], vec![], vec![]]);
    for l in [10.0, 20.0, 40.0, 80.0] {
        let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), ai).unwrap();
        let (rt_ij, rt_ji, rr) = pair_rot(&ew, 1.0, ai, aj, r.into()).unwrap();
        ls.push(l);
        for (k, (a, b)) in [(rt_ij, free.rt_ij), (rt_ji, free.rt_ji), (rr, free.rr)]
            .into_iter()
            .enumerate()
        {
            d[k].push(max_diff(&m64::<f64>(a), &m64::<f64>(b)));
        }
    }
    for (name, ds) in ["rt_ij", "rt_ji", "rr"].iter().zip(&d) {
        let slope = loglog_slope(&ls, ds);
        println!("{name}: |M_L - M_free| {ds:?}, slope {slope:.4}");
        assert!((slope + 3.0).abs() < 0.05, "{name}: slope {slope}");
    }
}

/// The spin from forces (`add_spin`: real blocks pair by pair, wave part through
/// structure factors) against the assembled `rt` blocks times the forces.
#[test]
fn spin_matches_assembly() {
    let size = [9.0, 10.0, 12.0];
    for seed in 0..4u64 {
        let (p, r) = config(8, seed, size, 2.0, seed % 2 == 1);
        let (pos, rad) = to_t::<f64>(&p, &r);
        let ew = Ewald::new(Periodic::new(size).unwrap(), 2.0).unwrap();
        let g = grand(&ew, &pos, &rad);
        let n = pos.len();
        let f: Vec<_> = (0..n)
            .map(|i| hydrorattle::glam::DVec3::new(1.0 + i as f64, -0.5 * i as f64, 0.3))
            .collect();
        let mut want = vec![hydrorattle::glam::DVec3::ZERO; n];
        for i in 0..n {
            for j in 0..n {
                // Row n + i, column j: below the diagonal, stored.
                want[i] += g[tri(n + i) + j] * f[j];
            }
        }
        let mut got = vec![hydrorattle::glam::DVec3::ZERO; n];
        add_spin(&ew, 1.0, &pos, &rad, &f, &mut got).unwrap();
        let scale = want
            .iter()
            .map(|v| v.abs().max_element())
            .fold(0.0, f64::max);
        let d = want
            .iter()
            .zip(&got)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f64::max);
        assert!(d < 1e-13 * scale, "seed {seed}: {d:e} of {scale:e}");
    }
}
