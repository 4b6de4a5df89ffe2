//! The Lanczos noise against exact answers, f64:
//! * its truncation error: `M^(1/2) z` and `M^(-1/2) z` from Lanczos against the roots
//!   from a dense eigen-decomposition of `M` done here (cyclic Jacobi on the `3N x 3N`
//!   matrix, nothing from the kernel but the assembled mobility), below the stated
//!   tolerance, on a 10-bead cluster and a 64-bead helix;
//! * the reduced copy of a large mobility the noise's products read
//!   (`noise::reduced`): its products against the mobility's, the noise through them
//!   against a converged root, and a thermal step through it against the matrix-free
//!   one (which reads no copy), on a 768-bead helix;
//! * a freely jointed chain of 64 beads with RPY and stiff constraints, through the
//!   Lanczos path with the midpoint drift: the stiff-bond equilibrium has independent
//!   bond directions, uniform on the sphere, so `<R_ee^2> = B b^2` and consecutive bonds
//!   have `<cos> = 0`. Chains start from exact samples of that law and the dynamics must
//!   keep it: each chain is a block (independent); `<R_ee^2>` is estimated as
//!   `B b^2 + mean(R^2(t) - R^2(0))` (a control variate whose expectation is exact by
//!   construction, so its standard error measures the dynamics' drift away from
//!   equilibrium, not the spread of the initial samples), `<cos>` as the mean over
//!   bonds, chains and recorded times; both within 3 standard errors.

use crate::common;

use common::*;
use hydrorattle::linalg::{self, tri};
use hydrorattle::mobility::assemble_tt;
use hydrorattle::noise::lanczos::{self, Lanczos};
use hydrorattle::noise::reduced;
use hydrorattle::parallel::band_scratch;
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, Particle,
    ParticleSet, Serial, SolverKind, step, step_slices,
};
use hydrorattle_heap::{Buffers, Spheres};

/// Dense `3n x 3n` mobility (row-major) from the packed one.
fn dense(mu: &[glam::DMat3], n: usize) -> Vec<f64> {
    let d = 3 * n;
    let mut a = vec![0.0; d * d];
    for i in 0..n {
        for j in 0..n {
            let b = if j <= i {
                mu[tri(i) + j]
            } else {
                mu[tri(j) + i].transpose()
            };
            for r in 0..3 {
                for c in 0..3 {
                    a[(3 * i + r) * d + 3 * j + c] = b.col(c)[r];
                }
            }
        }
    }
    a
}

/// Eigenvalues and eigenvectors (columns of the returned matrix) of the symmetric `a`
/// by cyclic Jacobi rotations, to round-off.
fn eigen(mut a: Vec<f64>, d: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0.0; d * d];
    for k in 0..d {
        v[k * d + k] = 1.0;
    }
    for _ in 0..100 {
        let off: f64 = (0..d)
            .flat_map(|p| (0..d).filter(move |&q| q != p).map(move |q| (p, q)))
            .map(|(p, q)| a[p * d + q].powi(2))
            .sum();
        if off < 1e-30 {
            break;
        }
        for p in 0..d {
            for q in p + 1..d {
                let apq = a[p * d + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * d + q] - a[p * d + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
                for k in 0..d {
                    let (akp, akq) = (a[k * d + p], a[k * d + q]);
                    a[k * d + p] = c * akp - s * akq;
                    a[k * d + q] = s * akp + c * akq;
                }
                for k in 0..d {
                    let (apk, aqk) = (a[p * d + k], a[q * d + k]);
                    a[p * d + k] = c * apk - s * aqk;
                    a[q * d + k] = s * apk + c * aqk;
                }
                for k in 0..d {
                    let (vkp, vkq) = (v[k * d + p], v[k * d + q]);
                    v[k * d + p] = c * vkp - s * vkq;
                    v[k * d + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..d).map(|k| a[k * d + k]).collect(), v)
}

/// `f(M) z` from the eigen-decomposition.
fn apply(lam: &[f64], v: &[f64], z: &[f64], f: impl Fn(f64) -> f64) -> Vec<f64> {
    let d = lam.len();
    let mut out = vec![0.0; d];
    for k in 0..d {
        let w: f64 = (0..d).map(|r| v[r * d + k] * z[r]).sum::<f64>() * f(lam[k]);
        for r in 0..d {
            out[r] += v[r * d + k] * w;
        }
    }
    out
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    (d / b.iter().map(|y| y * y).sum::<f64>()).sqrt()
}

#[test]
fn lanczos_truncation_error_is_below_the_stated_tolerance() {
    // A polydisperse 64-bead helix, and its first 10 beads.
    let mut spheres = helix(64, 2.0, 4.0, 1.0, 1.2);
    for (k, b) in spheres.iter_mut().enumerate().skip(1) {
        if k % 5 == 0 {
            b.radius = 0.6;
        }
    }
    for n in [10, 64] {
        let pos: Vec<glam::DVec3> = spheres[..n].iter().map(|s| s.pos.into()).collect();
        let radius: Vec<f64> = spheres[..n].iter().map(|s| s.radius).collect();
        let mut mu = vec![glam::DMat3::ZERO; tri(n)];
        assemble_tt(Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
        let (lam, v) = eigen(dense(&mu, n), 3 * n);
        assert!(lam.iter().all(|&l| l > 0.0));
        for tolerance in [1e-3, 1e-6] {
            let s = Lanczos {
                tolerance,
                max_iterations: 64,
            };
            let mut noise = Noise::new(5);
            let (mut worst_root, mut worst_inv) = (0.0f64, 0.0f64);
            let mut counts = Vec::new();
            for _ in 0..8 {
                let mut z = vec![glam::DVec3::ZERO; n];
                noise.fill::<f64>(&mut z);
                let mut basis = vec![glam::DVec3::ZERO; lanczos::vectors(64, n)];
                let mut work = vec![0.0; lanczos::scalars(64)];
                let (mut y, mut w) = (vec![glam::DVec3::ZERO; n], vec![glam::DVec3::ZERO; n]);
                let product = |x: &[glam::DVec3], o: &mut [glam::DVec3]| {
                    linalg::sym_matvec::<f64>(&mu, n, x, o)
                };
                let m = lanczos::sqrt(s, product, &z, &mut basis, &mut work, &mut y, Some(&mut w))
                    .unwrap();
                counts.push(m);
                let flat = |a: &[glam::DVec3]| -> Vec<f64> {
                    a.iter().flat_map(|p| p.to_array()).collect()
                };
                let zf = flat(&z);
                worst_root = worst_root.max(rel(&flat(&y), &apply(&lam, &v, &zf, f64::sqrt)));
                worst_inv =
                    worst_inv.max(rel(&flat(&w), &apply(&lam, &v, &zf, |l| 1.0 / l.sqrt())));
            }
            println!(
                "N = {n}, tolerance {tolerance:e}: iterations {counts:?}, relative error \
                 M^1/2 z {worst_root:.2e}, M^-1/2 z {worst_inv:.2e}"
            );
            assert!(worst_root < tolerance, "M^1/2 z off by {worst_root:e}");
            assert!(worst_inv < tolerance, "M^-1/2 z off by {worst_inv:e}");
        }
    }
}

/// The copy's product against the mobility's on general symmetric blocks, for row
/// counts around the lane groups, with one band (below `BANDED_MIN`) and with sixteen.
#[test]
fn reduced_product_matches_the_mobility() {
    use glam::{DMat3, DVec3};
    for n in [1, 2, 3, 4, 5, 6, 7, 8, 9, 17, 40, 600, 700] {
        let f = |k: usize, s: f64| (k as f64 * s).sin();
        let mu: Vec<DMat3> = (0..tri(n))
            .map(|k| {
                let (a, b, c) = (f(k, 0.7), f(k, 1.3), f(k, 2.1));
                DMat3::from_cols_array(&[2.0 + a, b, c, b, 2.0 - a, a * b, c, a * b, 2.0 + c])
            })
            .collect();
        let x: Vec<DVec3> = (0..n)
            .map(|k| DVec3::new(f(k, 0.3), f(k, 0.5), 1.0))
            .collect();
        let (mut y, mut exact) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        let mut store = vec![DMat3::ZERO; reduced::slots(n)];
        let mut sc = vec![DVec3::ZERO; band_scratch(n)];
        reduced::copy_apply::<f64>(&Serial, &mu, n, &mut store, &x, &mut y, &mut sc);
        linalg::sym_matvec::<f64>(&mu, n, &x, &mut exact);
        let scale = (n as f64).sqrt() * 1e-6;
        for (i, (a, b)) in y.iter().zip(&exact).enumerate() {
            let off = (*a - *b).length();
            assert!(
                off < scale * b.length().max(1.0),
                "n = {n}, row {i}: {a} against {b}"
            );
        }
    }
}

#[test]
fn reduced_copy_keeps_the_noise_within_the_tolerance() {
    use glam::DVec3;
    let n = reduced::REDUCED_MIN + 68;
    let spheres = helix(n, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let pos: Vec<DVec3> = spheres.iter().map(|s| s.pos.into()).collect();
    let radius: Vec<f64> = spheres.iter().map(|s| s.radius).collect();
    let mut mu = vec![glam::DMat3::ZERO; tri(n)];
    assemble_tt(Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
    // The copy's products: the same bits whether written on the way or read back, and
    // the mobility's to the rounding of its entries to `f32` and the `f32` sums.
    let mut packed = vec![glam::DMat3::ZERO; reduced::slots(n)];
    let mut sc = vec![DVec3::ZERO; band_scratch(n)];
    let mut z = vec![DVec3::ZERO; n];
    Noise::new(3).fill::<f64>(&mut z);
    let (mut a, mut b, mut exact) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n], vec![]);
    exact.resize(n, DVec3::ZERO);
    reduced::copy_apply::<f64>(&Serial, &mu, n, &mut packed, &z, &mut a, &mut sc);
    reduced::apply::<f64>(&Serial, &packed, n, &z, &mut b, &mut sc);
    assert_eq!(a, b);
    linalg::sym_matvec::<f64>(&mu, n, &z, &mut exact);
    let flat = |a: &[DVec3]| -> Vec<f64> { a.iter().flat_map(|p| p.to_array()).collect() };
    let off = rel(&flat(&a), &flat(&exact));
    println!("N = {n}: reduced product off by {off:.2e} (relative)");
    assert!(off < 1e-6, "reduced product off by {off:e}");
    // The noise through the copy against a converged root from the mobility itself.
    let mut basis = vec![DVec3::ZERO; lanczos::vectors(64, n)];
    let mut work = vec![0.0; lanczos::scalars(64)];
    let (mut root, mut inv) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let (mut root_ref, mut inv_ref) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    let full = |x: &[DVec3], o: &mut [DVec3]| linalg::sym_matvec::<f64>(&mu, n, x, o);
    let tight = Lanczos {
        tolerance: 1e-7,
        max_iterations: 64,
    };
    let (w, r) = (&mut basis, &mut work);
    lanczos::sqrt(tight, full, &z, w, r, &mut root_ref, Some(&mut inv_ref)).unwrap();
    let mut first = true;
    let copy = |x: &[DVec3], o: &mut [DVec3]| match std::mem::take(&mut first) {
        true => reduced::copy_apply::<f64>(&Serial, &mu, n, &mut packed, x, o, &mut sc),
        false => reduced::apply::<f64>(&Serial, &packed, n, x, o, &mut sc),
    };
    let s = Lanczos::default();
    let m = lanczos::sqrt(s, copy, &z, w, r, &mut root, Some(&mut inv)).unwrap();
    let (e_root, e_inv) = (
        rel(&flat(&root), &flat(&root_ref)),
        rel(&flat(&inv), &flat(&inv_ref)),
    );
    println!("N = {n}: {m} iterations, relative error M^1/2 z {e_root:.2e}, M^-1/2 z {e_inv:.2e}");
    assert!(e_root < s.tolerance && e_inv < s.tolerance);
    // A thermal step through the copy against the matrix-free one (no copy): the same
    // step but for the noise's error, and the bonds held.
    let bonds = chain_bonds(&pos);
    let run = |matrix_free: bool| {
        let mut p = params::<f64>(0.01, Method::Overdamped, SolverKind::Krylov);
        p.allow_overlap = true;
        p.brownian = Some(Brownian::new(1.0));
        p.noise_sqrt = NoiseSqrt::Lanczos;
        p.matrix_free = matrix_free;
        let mut store = Buffers::<f64>::new(Layout::for_params(&p, n, n - 1));
        let mut s = Spheres::at_rest(pos.clone(), radius.clone(), vec![RHO; n]);
        s.noise = Some(Noise::new(7));
        let r = step_slices(s.state(), &bonds, &p, &mut store.workspace(), &mut NoForce).unwrap();
        (s.pos, r)
    };
    let ((x, r), (x_free, r_free)) = (run(false), run(true));
    assert!(r.noise_iterations > 2 && r.residual < 1e-6, "{r:?}");
    let size = |d: &mut dyn Iterator<Item = DVec3>| d.map(|v| v.length_squared()).sum::<f64>();
    let moved = size(&mut x_free.iter().zip(&pos).map(|(a, b)| *a - *b));
    let apart = size(&mut x.iter().zip(&x_free).map(|(a, b)| *a - *b));
    let gap = (apart / moved).sqrt(); // the copy's f32 entries and sums, not 1e-3
    println!("step: {r:?}\nmatrix-free: {r_free:?}\nrelative gap {gap:.2e}");
    assert!(
        gap < 1e-5,
        "step through the copy off by {gap:e} of the move"
    );
    // Golden digest of the step through the copy (FNV-1a over the positions' bits): the
    // f32 lanes' arithmetic is fixed (`glam::Vec4`, no fused multiply-add), so it is the
    // same on every target and thread count. It moves only when that arithmetic changes
    // on purpose; then re-pin from the printed value.
    let digest = fnv1a(x.iter().flat_map(|v| v.to_array().map(f64::to_bits)));
    println!("golden reduced-copy step: got {digest:#018x}");
    assert_eq!(
        digest, REDUCED_STEP,
        "golden digest of the step through the copy changed"
    );
}

/// [`reduced_copy_keeps_the_noise_within_the_tolerance`]'s step through the copy.
const REDUCED_STEP: u64 = 0x86ac_06d6_715f_7f6c;

const N: usize = 64;
const B: usize = N - 1;
/// Bond length and bead radius (overlapping beads allowed: RPY's overlapping branch).
const BOND: f64 = 2.0;
const RADIUS: f64 = 1.0;

/// An exact freely jointed chain: independent bond directions uniform on the sphere.
fn fjc(noise: &mut Noise) -> Vec<Particle<f64>> {
    let mut at = [0.0; 3];
    let mut out = vec![Particle::new(at.into(), RADIUS, 1.0)];
    for _ in 1..N {
        let g = [noise.normal(), noise.normal(), noise.normal()];
        let u = scale(g, BOND / norm(g));
        at = add(at, u);
        out.push(Particle::new(at.into(), RADIUS, 1.0));
    }
    out
}

fn end_to_end(ps: &ParticleSet<f64, N>) -> f64 {
    (ps.pos[N - 1] - ps.pos[0]).length_squared()
}

fn mean_cos(ps: &ParticleSet<f64, N>) -> f64 {
    let b: Vec<glam::DVec3> = (1..N).map(|i| ps.pos[i] - ps.pos[i - 1]).collect();
    (1..B)
        .map(|k| b[k].normalize().dot(b[k - 1].normalize()))
        .sum::<f64>()
        / (B - 1) as f64
}

fn mean_se(x: &[f64]) -> (f64, f64) {
    let k = x.len() as f64;
    let m = x.iter().sum::<f64>() / k;
    let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

#[test]
fn freely_jointed_chain_keeps_its_equilibrium_through_the_lanczos_noise() {
    const CHAINS: usize = 16;
    const STEPS: usize = 120;
    let mut p = params::<f64>(0.2, Method::Overdamped, SolverKind::Auto);
    p.gravity = glam::DVec3::ZERO;
    p.allow_overlap = true;
    p.brownian = Some(Brownian {
        temperature: 1.0,
        drift: Drift::Midpoint,
    });
    p.noise_sqrt = NoiseSqrt::Lanczos;
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, N, B));
    let mut ws = buf.workspace();
    let mut draw = Noise::new(2024);
    let (mut dr2, mut cosines) = (Vec::new(), Vec::new());
    let (mut lanczos_its, mut steps) = (0u64, 0u64);
    for chain in 0..CHAINS {
        let start = fjc(&mut draw);
        let mut ps: ParticleSet<f64, N> = ParticleSet::from_slice(&start, true).unwrap();
        let bonds = BondSet::<f64, B>::chain(&ps.pos[..N]).unwrap();
        ps.noise = Some(Noise::new(100 + chain as u64));
        let r0 = end_to_end(&ps);
        let mut cos = Vec::new();
        for s in 0..STEPS {
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
                .unwrap_or_else(|e| panic!("chain {chain} step {s}: {e}"));
            lanczos_its += u64::from(r.noise_iterations);
            steps += 1;
            if (s + 1) % 30 == 0 {
                cos.push(mean_cos(&ps));
            }
        }
        dr2.push(end_to_end(&ps) - r0);
        cosines.push(cos.iter().sum::<f64>() / cos.len() as f64);
        // Stiff constraints: every bond still at its length.
        for k in 1..N {
            let l = (ps.pos[k] - ps.pos[k - 1]).length();
            assert!((l - BOND).abs() < 1e-8 * BOND, "bond {k}: {l}");
        }
    }
    let exact = B as f64 * BOND * BOND;
    let (d, se_r) = mean_se(&dr2);
    let (c, se_c) = mean_se(&cosines);
    println!(
        "{CHAINS} chains x {STEPS} steps (dt {}), {:.1} Lanczos iterations a step: \
         <R_ee^2> = {:.2} +- {se_r:.2} (exact {exact}), <cos> = {c:.5} +- {se_c:.5} (exact 0)",
        p.dt,
        lanczos_its as f64 / steps as f64,
        exact + d
    );
    assert!(d.abs() < 3.0 * se_r, "R_ee^2 off by {:.1} SE", d / se_r);
    assert!(c.abs() < 3.0 * se_c, "<cos> off by {:.1} SE", c / se_c);
    // The chains moved: the end-to-end distance changed by more than its standard error.
    let spread = (dr2.iter().map(|x| x * x).sum::<f64>() / CHAINS as f64).sqrt();
    assert!(
        spread > 0.05 * exact,
        "chains barely moved: rms change {spread:.2}"
    );
}
