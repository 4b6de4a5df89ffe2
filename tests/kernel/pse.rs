//! The PSE fast path (`mobility::pse`) against references it did not produce: the dense
//! Ewald path (`mobility::periodic`, summed to rounding) on random polydisperse
//! configurations with overlapping pairs, Hasimoto's expansion for a lone sphere, its own
//! independence of the splitting parameter, and positive definiteness as a property test.
#![allow(clippy::needless_range_loop)]

use crate::common;

use common::boxes::{config_radii, to_t};
use common::fuzz::Rng;
use hydrorattle::error::ParticleError;
use hydrorattle::linalg::{cholesky, tri};
use hydrorattle::mobility::periodic::{Ewald, Periodic, PeriodicError, assemble_tt, tt_product};
use hydrorattle::mobility::pse::{Part, Pse, PseError, PseStorage};
use hydrorattle::{Lanczos, Noise, Real};
use hydrorattle_heap::PseBuffers;
use proptest::prelude::*;

/// `M F` by PSE.
fn pse_apply<T: Real>(pse: &Pse<T>, pos: &[T::V3], rad: &[T], f: &[T::V3]) -> Vec<T::V3> {
    pse_part(Part::Both, pse, pos, rad, f)
}

/// One part of `M F` by PSE.
fn pse_part<T: Real>(
    part: Part,
    pse: &Pse<T>,
    pos: &[T::V3],
    rad: &[T],
    f: &[T::V3],
) -> Vec<T::V3> {
    let size = pse.storage(pos.len());
    let mut arrays = PseBuffers::new(size);
    let mut store = arrays.storage();
    let mut out = vec![T::V3_ZERO; pos.len()];
    pse.apply(part, T::ONE, pos, rad, f, &mut out, &mut store)
        .unwrap();
    out
}

/// `M F` by the Ewald path, in f64.
fn ewald_apply(size: [f64; 3], pos: &[[f64; 3]], rad: &[f64], f: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let ew = Ewald::new(Periodic::new(size).unwrap(), a_max).unwrap();
    let (p, r) = to_t::<f64>(pos, rad);
    let x: Vec<_> = f.iter().map(|&v| f64::v3_from(v)).collect();
    let mut y = vec![f64::V3_ZERO; pos.len()];
    tt_product(&ew, 1.0, &p, &r, &x, &mut y).unwrap();
    y.iter().map(|&v| f64::v3_to_f64(v)).collect()
}

fn forces(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed ^ 0xF0F0);
    (0..n)
        .map(|_| [0, 1, 2].map(|_| rng.range(-1.0, 1.0)))
        .collect()
}

/// `|a - b| / |b|` over all components.
pub(crate) fn rel_err(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for d in 0..3 {
            num += (x[d] - y[d]).powi(2);
            den += y[d] * y[d];
        }
    }
    (num / den).sqrt()
}

/// PSE's relative error against `want` for `tol`, at `xi a_max = 0.5 * xi_scale`
/// (`None`: the rule's own `xi`), with the parameters used.
fn rel_pse<T: Real>(
    size: [f64; 3],
    tol: f64,
    xi_scale: Option<f64>,
    (pos, rad): (&[[f64; 3]], &[f64]),
    f: &[[f64; 3]],
    want: &[[f64; 3]],
) -> (f64, Pse<T>) {
    let a_max = rad.iter().cloned().fold(0.0, f64::max);
    let cell = Periodic::new(size.map(T::from_f64)).unwrap();
    let a = T::from_f64(a_max);
    let pse = match xi_scale {
        None => Pse::new(cell, a, tol).unwrap(),
        Some(s) => Pse::with_xi(cell, a, tol, T::from_f64(s * 0.5 / a_max)).unwrap(),
    };
    let (p, r) = to_t::<T>(pos, rad);
    let x: Vec<_> = f.iter().map(|&v| T::v3_from(v)).collect();
    let got: Vec<[f64; 3]> = pse_apply(&pse, &p, &r, &x)
        .iter()
        .map(|&v| T::v3_to_f64(v))
        .collect();
    (rel_err(&got, want), pse)
}

/// Random polydisperse configurations (radii 0.5 to 1.5, half the spheres overlapping
/// another), cubic and rectangular boxes: PSE within each tolerance of the Ewald sum.
fn against_ewald<T: Real>(tols: &[f64]) {
    let mut worst = 0.0f64;
    for (size, n, seed) in [
        ([16.0; 3], 40, 1u64),
        ([14.0, 18.0, 22.0], 60, 2),
        ([20.0; 3], 80, 3),
        ([11.0, 24.0, 13.0], 50, 4),
        // A suspension: volume fraction about 0.1.
        ([22.0; 3], 200, 6),
    ] {
        let (pos, rad) = config_radii(n, seed, size, [0.5, 1.5], true);
        let f = forces(pos.len(), seed);
        let want = ewald_apply(size, &pos, &rad, &f);
        for &tol in tols {
            let (e, pse) = rel_pse::<T>(size, tol, None, (&pos, &rad), &f, &want);
            println!(
                "box {size:?} n {} tol {tol:e}: rel err {e:.2e} ({:.3} tol), grid {:?}, P {:?}, r_c {:.2}",
                pos.len(),
                e / tol,
                pse.grid(),
                pse.support(),
                pse.r_cut()
            );
            assert!(e < tol, "box {size:?} tol {tol:e}: {e:e}");
            worst = worst.max(e / tol);
        }
    }
    println!("worst error / tolerance {worst:.3}");
}

#[test]
fn against_ewald_f64() {
    against_ewald::<f64>(&[1e-3, 1e-4, 1e-5, 1e-6]);
}

/// f32: the tolerances its rounding (FFT sums of `~1e5` terms) leaves room for.
#[test]
fn against_ewald_f32() {
    against_ewald::<f32>(&[1e-3, 1e-4, 1e-5]);
}

/// The same product at three splitting parameters (`xi a_max = 0.35, 0.5, 0.7`):
/// agreement to the tolerance, though grid, support and cutoff all change.
#[test]
fn independent_of_splitting_parameter() {
    let size = [15.0, 17.0, 19.0];
    let (pos, rad) = config_radii(50, 9, size, [0.5, 1.5], true);
    let f = forces(pos.len(), 9);
    let want = ewald_apply(size, &pos, &rad, &f);
    for tol in [1e-3, 1e-5] {
        let runs: Vec<_> = [0.7, 1.0, 1.4]
            .map(|s| rel_pse::<f64>(size, tol, Some(s), (&pos, &rad), &f, &want))
            .into_iter()
            .collect();
        for (e, pse) in &runs {
            println!(
                "tol {tol:e} xi {:.3}: rel err {e:.2e}, grid {:?}, r_c {:.2}",
                pse.xi(),
                pse.grid(),
                pse.r_cut()
            );
            assert!(*e < tol);
        }
    }
}

/// Hasimoto's constant for the simple cubic lattice (Hasimoto, J. Fluid Mech. 5, 317,
/// 1959), to 13 digits.
const HASIMOTO: f64 = 2.837_297_479_480_6;

/// A lone sphere in a cubic box: `6 pi eta a u / F` against Hasimoto's
/// `1 - 2.837297 a/L + 4 pi/3 (a/L)^3` (exact for RPY, `docs/PERIODIC.md`), within the
/// tolerance, for `L/a` from 5 (cutoff beyond half the box: images in the near field)
/// to 60.
#[test]
fn hasimoto_lone_sphere() {
    for tol in [1e-4, 1e-6] {
        for l in [5.0, 10.0, 20.0, 60.0] {
            let pse = Pse::new(Periodic::new([l; 3]).unwrap(), 1.0f64, tol).unwrap();
            let x = 1.0 / l;
            let want = 1.0 - HASIMOTO * x + 4.0 / 3.0 * core::f64::consts::PI * x * x * x;
            let mut worst = 0.0f64;
            for dir in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
                let u = pse_apply(
                    &pse,
                    &[f64::v3(0.3, 1.7, 2.2)],
                    &[1.0],
                    &[f64::v3_from(dir)],
                );
                let u = f64::v3_to_f64(u[0]);
                for d in 0..3 {
                    let got = u[d] * 6.0 * core::f64::consts::PI;
                    let e = if dir[d] == 1.0 {
                        (got - want) / want
                    } else {
                        got / want
                    };
                    worst = worst.max(e.abs());
                }
            }
            println!(
                "tol {tol:e} L/a {l}: rel err {worst:.2e}, grid {:?}",
                pse.grid()
            );
            assert!(worst < tol, "L/a {l}: {worst:e}");
        }
    }
}

/// The PSE matrix, column by column (`3n` products), as packed 3x3 blocks of its
/// symmetric part, and the largest asymmetry relative to the largest entry.
fn assemble<T: Real>(part: Part, pse: &Pse<T>, pos: &[T::V3], rad: &[T]) -> (Vec<T::M3>, f64) {
    let n = pos.len();
    let mut cols = vec![vec![[0.0f64; 3]; n]; 3 * n];
    for j in 0..3 * n {
        let mut f = vec![T::V3_ZERO; n];
        let mut e = [T::ZERO; 3];
        e[j % 3] = T::ONE;
        f[j / 3] = T::v3(e[0], e[1], e[2]);
        cols[j] = pse_part(part, pse, pos, rad, &f)
            .iter()
            .map(|&v| T::v3_to_f64(v))
            .collect();
    }
    let get = |r: usize, c: usize| cols[c][r / 3][r % 3];
    let (mut asym, mut big) = (0.0f64, 0.0f64);
    let mut m = vec![T::M3_ZERO; tri(n)];
    for bi in 0..n {
        for bj in 0..=bi {
            let mut cols3 = [[T::ZERO; 3]; 3];
            for c in 0..3 {
                for r in 0..3 {
                    let (gr, gc) = (3 * bi + r, 3 * bj + c);
                    let (a, b) = (get(gr, gc), get(gc, gr));
                    asym = asym.max((a - b).abs());
                    big = big.max(a.abs());
                    cols3[c][r] = T::from_f64(0.5 * (a + b));
                }
            }
            m[tri(bi) + bj] = T::m3_cols(
                T::v3(cols3[0][0], cols3[0][1], cols3[0][2]),
                T::v3(cols3[1][0], cols3[1][1], cols3[1][2]),
                T::v3(cols3[2][0], cols3[2][1], cols3[2][2]),
            );
        }
    }
    (m, asym / big)
}

/// The PSE operator is symmetric (to rounding) and positive definite: its assembled
/// matrix has a Cholesky factor, and `F . M F > 0` for a random `F`.
fn positive_definite<T: Real>(n: usize, seed: u64, size: [f64; 3], overlap: bool, tol: f64) {
    let (p, r) = config_radii(n, seed, size, [0.5, 1.5], overlap);
    let a_max = r.iter().cloned().fold(0.0, f64::max);
    let cell = Periodic::new(size.map(T::from_f64)).unwrap();
    let pse = Pse::new(cell, T::from_f64(a_max), tol).unwrap();
    let (pos, rad) = to_t::<T>(&p, &r);
    let (mut m, asym) = assemble(Part::Both, &pse, &pos, &rad);
    let eps = T::EPSILON.to_f64();
    assert!(asym < 1e3 * eps, "asymmetry {asym:e}");
    cholesky::<T>(&mut m, pos.len()).unwrap();
    let f: Vec<_> = forces(pos.len(), seed)
        .iter()
        .map(|&v| T::v3_from(v))
        .collect();
    let u = pse_apply(&pse, &pos, &rad, &f);
    let q: f64 = f.iter().zip(&u).map(|(a, b)| T::dot(*a, *b).to_f64()).sum();
    assert!(q > 0.0, "F . M F = {q:e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn positive_definite_f64(n in 1usize..=8, seed in any::<u64>(), lx in 6.0f64..12.0, ly in 6.0f64..12.0, lz in 6.0f64..12.0, overlap in any::<bool>(), digits in 3i32..=6) {
        positive_definite::<f64>(n, seed, [lx, ly, lz], overlap, 10f64.powi(-digits));
    }
    #[test]
    fn positive_definite_f32(n in 1usize..=8, seed in any::<u64>(), lx in 6.0f64..12.0, ly in 6.0f64..12.0, lz in 6.0f64..12.0, overlap in any::<bool>(), digits in 3i32..=5) {
        positive_definite::<f32>(n, seed, [lx, ly, lz], overlap, 10f64.powi(-digits));
    }
}

/// The same inputs give the same bits (twice in one process, and the golden digest
/// across machines and versions; it changes only with the arithmetic).
#[test]
fn deterministic() {
    let size = [13.0, 14.0, 15.0];
    let (p, r) = config_radii(40, 5, size, [0.5, 1.5], true);
    let pse = Pse::new(Periodic::new(size).unwrap(), 1.5f64, 1e-4).unwrap();
    let (pos, rad) = to_t::<f64>(&p, &r);
    let f: Vec<_> = forces(pos.len(), 5)
        .iter()
        .map(|&v| f64::v3_from(v))
        .collect();
    let a = pse_apply(&pse, &pos, &rad, &f);
    let b = pse_apply(&pse, &pos, &rad, &f);
    let bits = |v: &[<f64 as Real>::V3]| -> Vec<u64> {
        v.iter()
            .flat_map(|&x| f64::v3_to_f64(x).map(f64::to_bits))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    // Golden: libm maths and a fixed order of every sum, so the same on every machine.
    assert_eq!(common::fnv1a(bits(&a)), 0x9280_6cbe_5b9c_4001);
}

/// Typed errors: tolerance, xi and radius out of range, a sphere nested in another's
/// image, non-finite input, short storage, mismatched lengths.
#[test]
fn errors() {
    let cell = Periodic::new([10.0; 3]).unwrap();
    let bad = |e: PeriodicError| Err::<Pse<f64>, _>(PseError::Periodic(e));
    assert_eq!(
        Pse::new(cell, 1.0, 0.5).map(|_| ()),
        bad(PeriodicError::BadParameter("tolerance")).map(|_| ())
    );
    assert_eq!(
        Pse::with_xi(cell, 1.0, 1e-4, -1.0).map(|_| ()),
        bad(PeriodicError::BadParameter("xi")).map(|_| ())
    );
    assert_eq!(
        Pse::new(cell, 5.0, 1e-4).map(|_| ()),
        bad(PeriodicError::SphereTooLarge).map(|_| ())
    );
    let pse = Pse::new(cell, 1.0, 1e-4).unwrap();
    let size = pse.storage(2);
    let mut arrays = PseBuffers::new(size);
    let mut store = arrays.storage();
    let mut out = vec![f64::V3_ZERO; 2];
    let f = [f64::v3(1.0, 0.0, 0.0); 2];
    // Nested through the boundary: centres 0.2 apart across the face, radii 1 and 0.5.
    let pos = [f64::v3(0.05, 5.0, 5.0), f64::v3(9.95, 5.0, 5.0)];
    let e = pse.apply(Part::Both, 1.0, &pos, &[1.0, 0.5], &f, &mut out, &mut store);
    assert_eq!(
        e,
        Err(PseError::Periodic(PeriodicError::Particle(
            ParticleError::Nested { i: 0, j: 1 }
        )))
    );
    let e = pse.apply(Part::Both, 1.0, &pos, &[1.0, 1.5], &f, &mut out, &mut store);
    assert_eq!(
        e,
        Err(PseError::Periodic(PeriodicError::Radius { particle: 1 }))
    );
    let e = pse.apply(
        Part::Both,
        1.0,
        &[pos[0], f64::v3(f64::NAN, 0.0, 0.0)],
        &[1.0, 1.0],
        &f,
        &mut out,
        &mut store,
    );
    assert_eq!(
        e,
        Err(PseError::Periodic(PeriodicError::Particle(
            ParticleError::NonFinite { particle: 1 }
        )))
    );
    let e = pse.apply(Part::Both, 1.0, &pos, &[1.0], &f, &mut out, &mut store);
    assert_eq!(e, Err(PseError::Length));
    let mut short = PseStorage::new(
        &mut arrays.complex[..10],
        &mut arrays.index,
        &mut arrays.vectors,
    );
    let e = pse.apply(Part::Both, 1.0, &pos, &[1.0, 1.0], &f, &mut out, &mut short);
    assert!(matches!(e, Err(PseError::Storage { .. })), "{e:?}");
    let mut short = PseStorage::new(
        &mut arrays.complex,
        &mut arrays.index,
        &mut arrays.vectors[..1],
    );
    let e = pse.apply(Part::Both, 1.0, &pos, &[1.0, 1.0], &f, &mut out, &mut short);
    assert!(
        matches!(
            e,
            Err(PseError::Storage {
                have: [_, _, 1],
                ..
            })
        ),
        "{e:?}"
    );
    println!("{}", PseError::GridTooLarge);
}

/// The real-space (near-field) part alone, the operator PSE's noise would take a
/// Lanczos square root of. With Beenakker's polynomial factors (this split) its
/// positivity is not guaranteed as with PSE's `sinc^2` split: the self block is
/// `1/(6 pi eta a) - xi/(2 pi^{3/2}) (1 - 10/9 x^2 + 7/9 x^4) / eta`, `x = xi a`, which is
/// negative from `x = 0.9426` on. Checked here against that closed form (a lone sphere
/// in a box large enough for no image within the cutoff), and the near part of random
/// configurations (radii 0.3 to 1.5, overlapping or not) is positive definite at the
/// rule's `xi a_max = 0.5` and at 0.3 (Cholesky), but not at `xi a_max = 1`.
#[test]
fn near_field_positivity() {
    let self_real = |x: f64| {
        1.0 / (6.0 * core::f64::consts::PI)
            - x / (2.0 * core::f64::consts::PI.powf(1.5))
                * (1.0 - 10.0 / 9.0 * x * x + 7.0 / 9.0 * x.powi(4))
    };
    for x in [0.3, 0.5, 0.94, 1.0] {
        let pse = Pse::with_xi(Periodic::new([60.0; 3]).unwrap(), 1.0f64, 1e-4, x).unwrap();
        let u = pse_part(
            Part::Near,
            &pse,
            &[f64::v3(1.0, 2.0, 3.0)],
            &[1.0],
            &[f64::v3(1.0, 0.0, 0.0)],
        );
        let got = f64::v3_to_f64(u[0])[0];
        assert!(
            (got - self_real(x)).abs() < 1e-14,
            "xi a {x}: {got} vs {}",
            self_real(x)
        );
    }
    assert!(self_real(0.942) > 0.0 && self_real(0.943) < 0.0);
    let mut not_pd = [0usize; 3];
    for seed in 0..6u64 {
        for (size, n, lo) in [([8.0; 3], 12, 0.5), ([6.0; 3], 14, 0.3)] {
            let (p, r) = config_radii(n, seed, size, [lo, 1.5], seed % 2 == 0);
            let a_max = r.iter().cloned().fold(0.0, f64::max);
            let (pos, rad) = to_t::<f64>(&p, &r);
            for (k, x) in [0.3, 0.5, 1.0].into_iter().enumerate() {
                let pse =
                    Pse::with_xi(Periodic::new(size).unwrap(), a_max, 1e-4, x / a_max).unwrap();
                let (mut m, _) = assemble(Part::Near, &pse, &pos, &rad);
                not_pd[k] += cholesky::<f64>(&mut m, pos.len()).is_err() as usize;
            }
        }
    }
    println!("near part not positive definite (of 12) at xi a_max = 0.3, 0.5, 1: {not_pd:?}");
    assert_eq!(not_pd[..2], [0, 0]);
    assert_eq!(not_pd[2], 12);
}

/// PSE's Brownian displacement has covariance `M`: the sample covariance of 4000 draws
/// against the Ewald path's assembled mobility (PSE's own operator is within `tol =
/// 1e-4` of it, far below the statistical error), entry by entry within 5 standard
/// errors and in its trace within 4, for 3 polydisperse spheres (an overlapping pair)
/// and for 4 equal ones, at the rule's `xi`. The real-space part is a tenth to a half of
/// the diagonal here, far above the statistical error, so dropping either half fails.
#[test]
fn noise_covariance() {
    for (size, n, seed) in [([8.0, 9.0, 10.0], 3, 21u64), ([7.0; 3], 4, 4)] {
        let (p, r) = config_radii(n, seed, size, [0.6, 1.4], n == 3);
        let n = p.len();
        let a_max = r.iter().cloned().fold(0.0, f64::max);
        let pse = Pse::new(Periodic::new(size).unwrap(), a_max, 1e-4).unwrap();
        let (pos, rad) = to_t::<f64>(&p, &r);
        let ew = Ewald::new(Periodic::new(size).unwrap(), a_max).unwrap();
        let mut m = vec![f64::M3_ZERO; tri(n)];
        assemble_tt(&ew, 1.0, &pos, &rad, &mut m).unwrap();
        let (near, _) = assemble(Part::Near, &pse, &pos, &rad);
        let get = |m: &[<f64 as Real>::M3], a: usize, b: usize| {
            let blk = hydrorattle::linalg::sym_get::<f64>(m, a / 3, b / 3);
            f64::m3_get(blk, a % 3, b % 3)
        };
        let s = Lanczos {
            tolerance: 1e-8,
            max_iterations: 3 * n as u32,
        };
        let size = pse.storage(n);
        let mut arrays = PseBuffers::new(size);
        let mut store = arrays.storage();
        let (nv, ns) = Pse::noise_storage(&s, n);
        let (mut basis, mut work) = (vec![f64::V3_ZERO; nv], vec![0.0; ns]);
        let mut rng = Noise::new(seed);
        let samples = 4000;
        let dim = 3 * n;
        let mut c = vec![0.0; dim * dim];
        let mut u = vec![f64::V3_ZERO; n];
        for _ in 0..samples {
            pse.noise(
                1.0,
                (&pos, &rad),
                &mut rng,
                s,
                &mut u,
                &mut store,
                (&mut basis, &mut work),
            )
            .unwrap();
            let x: Vec<f64> = u.iter().flat_map(|&w| f64::v3_to_f64(w)).collect();
            for a in 0..dim {
                for b in 0..dim {
                    c[a * dim + b] += x[a] * x[b] / samples as f64;
                }
            }
        }
        let mut worst = 0.0f64;
        for a in 0..dim {
            for b in 0..dim {
                let want = get(&m, a, b);
                let se = ((get(&m, a, a) * get(&m, b, b) + want * want) / samples as f64).sqrt();
                let z = (c[a * dim + b] - want) / se;
                worst = worst.max(z.abs());
            }
            let share = get(&near, a, a) / get(&m, a, a);
            let se = (2.0 / samples as f64).sqrt();
            assert!(
                share > 10.0 * se,
                "real-space share {share:.3} not above the noise"
            );
        }
        // The trace, the sharper test of the scale: var(sum x_a^2) = 2 sum M_ab^2.
        let (tc, tm) = (0..dim).fold((0.0, 0.0), |(x, y), a| {
            (x + c[a * dim + a], y + get(&m, a, a))
        });
        let m2: f64 = (0..dim * dim)
            .map(|k| get(&m, k / dim, k % dim).powi(2))
            .sum();
        let zt = (tc - tm) / (2.0 * m2 / samples as f64).sqrt();
        println!("n {n}: worst |C - M| / standard error {worst:.2}, trace {zt:.2}");
        assert!(worst < 5.0, "covariance off by {worst:.2} standard errors");
        assert!(zt.abs() < 4.0, "trace off by {zt:.2} standard errors");
    }
}
