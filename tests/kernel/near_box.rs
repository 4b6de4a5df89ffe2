//! Steps with Stokesian dynamics' near field in the periodic box (`Params::near` with
//! `Params::periodic`, the Ewald sums' far field), against values found independently:
//! the free-space near step (itself checked against Stimson and Jeffery's exact series in
//! `near_step.rs`) shifted by the box's known `O(a / L)` correction, Hasimoto's constant
//! (a pair's translation blocks at `r << L` each shift by `-2.837297 / (6 pi eta L)`,
//! rotation by `O((a / L)^3)`); positive definiteness as a property (the Cholesky factor
//! of the noise exists for every suspension drawn); the same bits run to run; and the
//! refusals, typed. Units: `a = 1`, `eta = 1`, buoyant weight 1, `U0 = 1 / (6 pi)`.
#![cfg(all(feature = "near", feature = "periodic"))]

use crate::common;
use crate::stokesian::stimson_jeffery;

use std::f64::consts::PI;

use common::*;
use hydrorattle::stokesian::NearField;
use hydrorattle::{
    BondSet, Brownian, Drift, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Periodic,
    Real, SolverKind, StepError, step,
};
use hydrorattle_heap::Buffers;
use proptest::prelude::*;

/// Stokes' speed of the unit sphere of unit buoyant weight in the unit fluid.
const U0: f64 = 1.0 / (6.0 * PI);
/// Density of unit buoyant weight for a unit sphere (`g = 1`).
const RHO1: f64 = 3.0 / (4.0 * PI);
/// Hasimoto's constant (see the module).
const HASIMOTO: f64 = 2.837297;

/// One vector a sphere.
type Vecs = Vec<[f64; 3]>;

/// Near-field parameters with the defaults, in the cubic box of edge `l` if given.
fn near<T: Real>(method: Method, l: Option<f64>) -> hydrorattle::Params<T> {
    let mut p = params::<T>(1e-2, method, SolverKind::Auto);
    p.near = Some(NearField::default());
    p.periodic = l.map(|l| Periodic::new([T::from_f64(l); 3]).unwrap());
    p
}

/// `steps` steps of `spheres` (unbonded) under `p` with the noise of `seed`; positions,
/// velocities and spins after them.
fn run<T: Real, const N: usize>(
    p: &hydrorattle::Params<T>,
    spheres: &[Sphere],
    steps: usize,
    seed: u64,
) -> Result<(Vecs, Vecs, Vecs), StepError> {
    let mut ps: ParticleSet<T, N> = particles(spheres);
    let bonds: BondSet<T, N> = BondSet::new();
    let mut buf = Buffers::<T>::new(Layout::for_params(p, spheres.len(), 0));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(seed);
    for _ in 0..steps {
        match p.brownian {
            Some(_) => step_thermal(&mut ps, &bonds, p, &mut ws, &mut NoForce, &mut noise)?,
            None => step(&mut ps, &bonds, p, &mut ws, &mut NoForce)?,
        };
    }
    let n = spheres.len();
    let get = |v: &[T::V3]| (0..n).map(|i| f64s::<T>(v[i])).collect();
    Ok((get(&ps.pos), get(&ps.vel), get(&ps.omega)))
}

/// Two unit spheres of unit weight, centres `s` apart along `axis`, about `c`.
fn pair(s: f64, axis: [f64; 3], c: [f64; 3]) -> [Sphere; 2] {
    let d = scale(axis, s / 2.0);
    [
        Sphere {
            pos: sub(c, d),
            radius: 1.0,
            density: RHO1,
        },
        Sphere {
            pos: add(c, d),
            radius: 1.0,
            density: RHO1,
        },
    ]
}

/// A pair at `s = 2.1` in a box of edge 100 falls as in free space less the box's
/// correction: each sphere's speed shifts by `-2 HASIMOTO / L` in `U0` (both spheres'
/// weights, within 10 % of that shift, which is itself 5.7 % of `U0`, so the box is
/// seen), along and across the line of centres; the spin by less than `HASIMOTO / L`
/// of itself (the shift's share of a sphere's mobility). With
/// both overdamped methods, and across a face of the box (the pair's minimum image).
fn pair_in_a_big_box<T: Real>() {
    let l = 100.0;
    let shift = 2.0 * HASIMOTO / l * U0;
    let tol = pick::<T>(0.15, 0.1);
    for method in [Method::Overdamped, Method::Overdamped2] {
        for (axis, want) in [
            ([0.0, 0.0, 1.0], stimson_jeffery(2.1) * U0),
            ([1.0, 0.0, 0.0], 1.3917 * U0),
        ] {
            let mut p = near::<T>(method, None);
            p.rotation = true;
            let (_, free, w_free) = run::<T, 2>(&p, &pair(2.1, axis, [0.0; 3]), 1, 1).unwrap();
            p.periodic = Some(Periodic::new([T::from_f64(l); 3]).unwrap());
            // Centred in the box, and astride the face x = 0 (images 100 apart).
            for c in [[50.0, 50.0, 50.0], [0.0, 50.0, 50.0]] {
                let (_, boxed, w_box) = run::<T, 2>(&p, &pair(2.1, axis, c), 1, 1).unwrap();
                for i in 0..2 {
                    let e = (-free[i][2] / want - 1.0).abs();
                    assert!(e < 5e-3, "{method:?} {axis:?}: free {}", -free[i][2] / U0);
                    let d = boxed[i][2] - free[i][2];
                    let miss = (d / shift - 1.0).abs();
                    assert!(
                        miss < tol,
                        "{method:?} {axis:?} {c:?}: shift {d:e} vs {shift:e}"
                    );
                    // The spin moves only through the translation shift's share in the
                    // inversion of `R` (the periodic rotlet's own change is
                    // `O(a / L)^3`): by less than that shift's fraction of a sphere's
                    // mobility.
                    let dw = norm(sub(w_box[i], w_free[i]));
                    let w = norm(w_free[i]).max(1e-3 * U0);
                    let bound = HASIMOTO / l * w + pick::<T>(1e-6, 1e-12);
                    assert!(dw < bound, "spin {dw:e} of {w:e}");
                }
            }
        }
    }
}

both_precisions! {
    pair_in_the_box => pair_in_a_big_box;
}

/// Spheres whose surfaces are 0.01 to 2 radii apart, some across the box's faces.
fn spheres() -> impl Strategy<Value = Vec<Sphere>> {
    let l = 8.0;
    (
        2usize..7,
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.01..2.0f64), 6),
    )
        .prop_map(move |(n, draws)| {
            let mut out: Vec<Sphere> = Vec::new();
            let mut c = [l - 1.2, 0.5 * l, 0.5 * l];
            for (k, &(u, v, gap)) in draws.iter().take(n).enumerate() {
                // Each next sphere at `2 + gap` from the last, in a direction of (u, v).
                if k > 0 {
                    let (th, ph) = (PI * u, 2.0 * PI * v);
                    let e = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
                    c = add(c, scale(e, 2.0 + gap));
                }
                let clear = out.iter().all(|s| {
                    let d = sub(s.pos, c).map(|x| x - l * (x / l).round());
                    norm(d) > 2.0 + 1e-3
                });
                if clear {
                    out.push(Sphere {
                        pos: c,
                        radius: 1.0,
                        density: RHO1,
                    });
                }
            }
            out
        })
}

/// A Brownian step (noise by Cholesky, rotation on) of the spheres in a box of edge 8:
/// `Ok` (the factor of `M_SD,tt` exists, so it is positive definite at the start and the
/// midpoint) and finite.
fn brownian_steps<T: Real>(spheres: &[Sphere]) -> Result<(), TestCaseError> {
    let mut p = near::<T>(Method::Overdamped, Some(8.0));
    p.rotation = true;
    p.brownian = Some(Brownian::new(T::ONE));
    p.noise_sqrt = NoiseSqrt::Cholesky;
    p.dt = T::from_f64(1e-4);
    let got = match spheres.len() {
        n if n <= 6 => run::<T, 6>(&p, spheres, 2, 7),
        _ => unreachable!(),
    };
    let (pos, _, w) = got.map_err(|e| TestCaseError::fail(format!("{e}")))?;
    prop_assert!(pos.iter().chain(&w).flatten().all(|x| x.is_finite()));
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn noise_factor_exists_f64(s in spheres()) {
        brownian_steps::<f64>(&s)?;
    }

    #[test]
    fn noise_factor_exists_f32(s in spheres()) {
        brownian_steps::<f32>(&s)?;
    }
}

/// Three close spheres in a box of edge 10, Brownian with rotation: two runs give the
/// same bits; the midpoint drift is applied (the box's unbonded RPY step drops it, its
/// divergence being zero, but `M_SD`'s is not): the uncorrected draw ends elsewhere.
#[test]
fn brownian_in_the_box_same_bits_and_midpoint() {
    let spheres = [
        Sphere {
            pos: [1.0, 5.0, 5.0],
            radius: 1.0,
            density: RHO1,
        },
        Sphere {
            pos: [3.55, 5.0, 5.0],
            radius: 1.5,
            density: RHO1,
        },
        Sphere {
            pos: [8.95, 5.0, 5.0],
            radius: 1.0,
            density: RHO1,
        },
    ];
    let mut p = near::<f64>(Method::Overdamped, Some(10.0));
    p.rotation = true;
    p.brownian = Some(Brownian::new(1.0));
    p.noise_sqrt = NoiseSqrt::Cholesky;
    p.dt = 1e-3;
    let a = run::<f64, 3>(&p, &spheres, 5, 11).unwrap();
    let b = run::<f64, 3>(&p, &spheres, 5, 11).unwrap();
    let bits = |v: &(Vecs, Vecs, Vecs)| -> Vec<u64> {
        [&v.0, &v.1, &v.2]
            .iter()
            .flat_map(|x| x.iter().flatten().map(|y| y.to_bits()))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    p.brownian = Some(Brownian {
        temperature: 1.0,
        drift: Drift::Uncorrected,
    });
    let c = run::<f64, 3>(&p, &spheres, 5, 11).unwrap();
    assert_ne!(bits(&a), bits(&c), "the midpoint was dropped");
}

/// What the near field in a box does not serve is refused, typed and named: the PSE
/// sums (no blocks to form `M_SD` from).
#[test]
fn pse_with_the_near_field_is_refused() {
    let mut p = near::<f64>(Method::Overdamped, Some(20.0));
    p.pse = Some(1e-3);
    let e = run::<f64, 2>(&p, &pair(2.5, [0.0, 0.0, 1.0], [10.0; 3]), 1, 1).unwrap_err();
    match e {
        StepError::Unsupported(what) => assert!(what.contains("PSE"), "{what}"),
        e => panic!("{e:?}"),
    }
}

/// `M_SD` is formed once per stage: the first-order step once, the predictor-corrector
/// twice, and a Brownian step with rotation twice (the start, the midpoint; its spins
/// read the start's rotation-translation blocks kept from the start's formation, not a
/// third formation), in free space and in the box. The Brownian step's spins are the
/// deterministic step's, bit for bit (unbonded, so the force is the weight alone, and
/// both read `M_SD,rt` formed at the start by the same code).
#[test]
fn m_sd_is_formed_once_a_stage() {
    let mut spheres = pair(2.1, [1.0, 0.0, 0.0], [5.0, 5.0, 5.0]).to_vec();
    spheres.push(Sphere {
        pos: [5.0, 5.0, 7.2],
        radius: 0.5,
        density: RHO1,
    });
    for l in [None, Some(12.0)] {
        let formed = |method: Method, thermal: bool| {
            let mut p = near::<f64>(method, l);
            p.rotation = true;
            if thermal {
                p.brownian = Some(Brownian::new(1.0));
                p.noise_sqrt = NoiseSqrt::Cholesky;
            }
            let mut ps: ParticleSet<f64, 3> = particles(&spheres);
            let bonds: BondSet<f64, 3> = BondSet::new();
            let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 3, 0));
            let mut ws = buf.workspace();
            let mut noise = Noise::new(3);
            let r = match thermal {
                true => step_thermal(&mut ps, &bonds, &p, &mut ws, &mut NoForce, &mut noise),
                false => step(&mut ps, &bonds, &p, &mut ws, &mut NoForce),
            }
            .unwrap();
            let spins: Vec<u64> = ps
                .omega
                .iter()
                .flat_map(|&w| f64s::<f64>(w))
                .map(|x| x.to_bits())
                .collect();
            (r.near_formations, spins)
        };
        let (one, w_det) = formed(Method::Overdamped, false);
        let (two, _) = formed(Method::Overdamped2, false);
        let (thermal, w_th) = formed(Method::Overdamped, true);
        assert_eq!((one, two, thermal), (1, 2, 2), "box {l:?}");
        assert_eq!(w_det, w_th, "box {l:?}: spins");
    }
}

/// The start's `M_SD,rt` kept for the spins takes `(3n)^2` scalars more, only in a
/// Brownian step with rotation (the one whose midpoint takes the dense matrix).
#[test]
fn kept_spins_storage_only_with_rotation_and_noise() {
    let n = 5;
    let layout = |rotation: bool, thermal: bool| {
        let mut p = near::<f64>(Method::Overdamped, None);
        p.rotation = rotation;
        if thermal {
            p.brownian = Some(Brownian::new(1.0));
            p.noise_sqrt = NoiseSqrt::Cholesky;
        }
        Layout::for_params(&p, n, 0)
    };
    assert_eq!(layout(true, false), layout(false, false));
    let (with, without) = (layout(true, true), layout(false, true));
    assert_eq!(with.scalars, without.scalars + 9 * n * n);
    assert_eq!(
        (with.blocks, with.vectors),
        (without.blocks, without.vectors)
    );
}
