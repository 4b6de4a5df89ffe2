//! The bead-spring model at temperature: a Hookean dumbbell's
//! equilibrium against its exact distribution.
//!
//! Two spheres joined by a spring `U = H (Q - d)^2 / 2` in free space: whatever the
//! mobility, the equilibrium of the bond vector `Q` is `p(Q) ~ Q^2 exp(-U / kT)` (the
//! RPY mobility has zero divergence, so no drift term is missing). Hence
//! `<Q^2> = M4 / M2` with `Mk = int_0^inf Q^k exp(-H (Q - d)^2 / 2kT) dQ`, computed
//! here by Simpson's rule (d = 0 gives the classic `3 kT / H`). Checked with free
//! draining (uncorrected noise) and with RPY (Fixman midpoint), each within 3 block
//! standard errors, and the standard error asserted small enough (below 1 %) that a
//! wrong noise amplitude (twice the variance) would fail by far.
//!
//! FENE dumbbell (force `-H Q / (1 - Q^2 / Q0^2)`): `p(Q) ~ Q^2 (1 - Q^2/Q0^2)^(b/2)`,
//! `b = H Q0^2 / kT`, so `<Q^2> = 3 kT / H * b / (b + 5)` (Bird et al., Dynamics of
//! Polymeric Liquids vol. 2). A step that would stretch the spring to `Q0` is refused;
//! the test retries it as 2, 4, ... sub-steps along the Brownian bridge
//! (`Noise::split`), as the demo does, and counts the retries.

use hydrorattle::glam::DVec3;
use hydrorattle::{
    Bond, BondError, BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, Params,
    Particle, ParticleSet, StepError, Workspace, step,
};
use hydrorattle_heap::Buffers;

/// `<Q^2>` of `p(Q) ~ Q^2 exp(-h (Q - d)^2 / 2)` (h = H / kT), Simpson on [0, d + 12/sqrt h].
fn exact_q2(h: f64, d: f64) -> f64 {
    let top = d + 12.0 / h.sqrt();
    let m = 20_000;
    let w = top / m as f64;
    let (mut m2, mut m4) = (0.0, 0.0);
    for k in 0..=m {
        let q = k as f64 * w;
        let c = if k == 0 || k == m {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let e = (-h * (q - d) * (q - d) / 2.0).exp();
        m2 += c * q * q * e;
        m4 += c * q.powi(4) * e;
    }
    m4 / m2
}

/// Mean and block standard error (50 blocks).
fn block_mean(x: &[f64]) -> (f64, f64) {
    let blocks = 50;
    let len = x.len() / blocks;
    let means: Vec<f64> = x
        .chunks_exact(len)
        .map(|c| c.iter().sum::<f64>() / len as f64)
        .collect();
    let m = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|b| (b - m) * (b - m)).sum::<f64>() / (blocks - 1) as f64;
    (m, (var / blocks as f64).sqrt())
}

/// A dumbbell of unit spheres at distance `q` (bond length `q` too, or 0 when
/// `rest_zero`), free space, `eta = 1/(6 pi)` (a lone sphere's mobility is 1), kT = 1,
/// spring `h`, time step `dt`, seed `seed`; the caller sets the rest.
fn setup(q: f64, h: f64, dt: f64, hydro: Hydro, drift: Drift, seed: u64) -> Dumbbell {
    setup_rest(q, q, h, dt, hydro, drift, seed)
}

/// [`setup`] with the spring's rest length `d` apart from the starting distance `q`.
fn setup_rest(q: f64, d: f64, h: f64, dt: f64, hydro: Hydro, drift: Drift, seed: u64) -> Dumbbell {
    let mut ps = ParticleSet::<f64, 2>::new();
    ps.push(Particle::new(DVec3::ZERO, 1.0, 0.0)).unwrap();
    ps.push(Particle::new(DVec3::new(q, 0.0, 0.0), 1.0, 0.0))
        .unwrap();
    let mut bonds = BondSet::<f64, 1>::new();
    bonds
        .push(
            Bond {
                i: 0,
                j: 1,
                length: d,
            },
            2,
        )
        .unwrap();
    let mut p = Params::<f64>::new(dt);
    p.method = Method::Springs;
    p.viscosity = 1.0 / (6.0 * std::f64::consts::PI);
    p.gravity = DVec3::ZERO;
    p.hydro = hydro;
    p.allow_overlap = true;
    p.spring_stiffness = h;
    p.brownian = Some(Brownian {
        temperature: 1.0,
        drift,
    });
    ps.noise = Some(Noise::new(seed));
    (ps, bonds, p)
}

type Dumbbell = (ParticleSet<f64, 2>, BondSet<f64, 1>, Params<f64>);

/// `<Q^2>` of a dumbbell of unit spheres, spring `h` (kT = 1), rest length `d`, time
/// step `dt`, `steps` steps.
fn dumbbell(
    hydro: Hydro,
    drift: Drift,
    h: f64,
    d: f64,
    dt: f64,
    steps: usize,
    seed: u64,
) -> (f64, f64) {
    // The bond relaxes at rate 2 h; it starts at its rest length (1.5 for rest length 0).
    let (mut ps, bonds, p) = setup_rest(d.max(1.5), d, h, dt, hydro, drift, seed);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 1));
    let mut ws = buf.workspace();
    let mut q2 = Vec::with_capacity(steps);
    for k in 0..steps {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        if k >= 2_000 {
            q2.push((ps.pos[0] - ps.pos[1]).length_squared());
        }
    }
    block_mean(&q2)
}

#[test]
fn hookean_dumbbell_equilibrium_free_draining_and_rpy() {
    let (h, d) = (1.0, 3.0);
    let exact = exact_q2(h, d);
    // The closed form at d = 0 checks the quadrature: <Q^2> = 3 kT / H.
    assert!((exact_q2(2.0, 0.0) - 1.5).abs() < 1e-9);
    for (hydro, drift, seed) in [
        (Hydro::FreeDraining, Drift::Uncorrected, 1),
        (Hydro::Rpy, Drift::Midpoint, 2),
    ] {
        let (m, se) = dumbbell(hydro, drift, h, d, 0.005, 1_000_000, seed);
        eprintln!("{hydro:?} {drift:?}: <Q^2> = {m:.4} +- {se:.4}, exact {exact:.4}");
        assert!(se < 0.01 * exact, "too few samples: se {se}");
        assert!(
            (m - exact).abs() < 3.0 * se,
            "{hydro:?}: {m} vs {exact} (se {se})"
        );
    }
}

/// The classic Hookean dumbbell: rest length zero, `<Q^2> = 3 kT / H` exactly. Time
/// step bias: Euler-Maruyama on the free-draining bond vector (relative mobility `2 /
/// zeta`, zeta = 1) is the discrete Ornstein-Uhlenbeck map `Q' = (1 - 2 H dt) Q +
/// noise`, whose stationary `<Q^2> = 3 kT / H / (1 - H dt)`: +0.2 % at `H dt = 0.002`
/// (dt is 1/250 of the relaxation time `zeta / 2H` of `Q`, 1/125 of the dumbbell's
/// `lambda_H = zeta / 4H`), a quarter of the standard error (0.8 %). With RPY the beads
/// overlap (`<Q^2>^(1/2) = 1.7 < 2a`) and the relative mobility is 2.5 times smaller
/// (`3 Q / 8` along the bond, `9 Q / 16` across, at `Q = 1.7`), so dt = 0.005 gives
/// the same bias and sampling.
fn hookean_rest_zero(hydro: Hydro, drift: Drift, dt: f64, seed: u64) {
    let h = 1.0;
    let exact = 3.0 / h;
    let (m, se) = dumbbell(hydro, drift, h, 0.0, dt, 2_000_000, seed);
    // The free-draining Euler-Maruyama map's own stationary value (see above).
    let map = exact / (1.0 - h * dt);
    eprintln!("rest length 0, {hydro:?} {drift:?}: <Q^2> = {m:.4} +- {se:.4}, exact {exact}");
    if hydro == Hydro::FreeDraining {
        eprintln!("(the discrete map's stationary value: {map:.4})");
    }
    assert!(se < 0.012 * exact, "too few samples: se {se}");
    assert!(
        (m - exact).abs() < 3.0 * se,
        "{hydro:?}: {m} vs {exact} (se {se})"
    );
}

#[test]
fn hookean_dumbbell_of_rest_length_zero_free_draining() {
    hookean_rest_zero(Hydro::FreeDraining, Drift::Uncorrected, 0.002, 5);
}

#[test]
fn hookean_dumbbell_of_rest_length_zero_rpy() {
    hookean_rest_zero(Hydro::Rpy, Drift::Midpoint, 0.005, 6);
}

/// Only a spring may have rest length zero: the bond list takes it, the spring step
/// runs it (its force `-H Q`, its report's largest force `H |Q|`), every constrained
/// method refuses it with a typed error, the state kept.
#[test]
fn rest_length_zero_is_for_springs_only() {
    let (mut ps, bonds, mut p) =
        setup_rest(1.5, 0.0, 2.0, 0.01, Hydro::FreeDraining, Drift::Midpoint, 1);
    p.brownian = None;
    ps.density = [1.0; 2];
    let mut buf = Buffers::<f64>::new(Layout::all(2, 1));
    let mut ws = buf.workspace();
    for method in [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
    ] {
        let mut q = p;
        q.method = method;
        let before = ps.clone();
        let e = step(&mut ps, &bonds, &q, &mut ws, &mut NoForce).unwrap_err();
        assert_eq!(
            e,
            StepError::Bond(BondError::BadLength { bond: 0 }),
            "{method:?}"
        );
        assert_eq!((ps.pos, ps.time), (before.pos, before.time));
    }
    // Free draining, no noise: each bead moves by H Q dt towards the other.
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
    let q = (ps.pos[1] - ps.pos[0]).x;
    assert!((q - 1.5 * (1.0 - 2.0 * 2.0 * 0.01)).abs() < 1e-14, "{q}");
    assert!((r.max_tension - 2.0 * q).abs() < 1e-12, "{}", r.max_tension);
    assert_eq!(r.residual, 0.0);
}

/// One step of `ps`; a refused one (FENE overstretch) retried as `2^d` bridge
/// sub-steps, `d = 1..=8`. Returns whether it was retried.
fn step_or_split<const N: usize, const B: usize>(
    ps: &mut ParticleSet<f64, N>,
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ws: &mut Workspace<'_, f64>,
) -> bool {
    let e = match step(ps, bonds, p, ws, &mut NoForce) {
        Ok(_) => return false,
        Err(e) => e,
    };
    assert!(
        matches!(e, StepError::Bond(BondError::Overstretched { .. })),
        "{e}"
    );
    let start = ps.clone();
    let base = ps.noise.clone().unwrap();
    for depth in 1..=8u8 {
        let mut q = *p;
        q.dt = p.dt / f64::from(1u32 << depth);
        let done = (0..1u32 << depth).all(|index| {
            ps.noise = Some(base.split(depth, index));
            step(ps, bonds, &q, ws, &mut NoForce).is_ok()
        });
        if done {
            ps.noise = ps.noise.take().map(Noise::join);
            return true;
        }
        *ps = start.clone();
    }
    panic!("a step refused even as 256 sub-steps");
}

/// The FENE dumbbell at dt = 0.002 (1/250 of the Hookean relaxation time `zeta / 2H`):
/// at the typical `Q^2 = 2` the spring is `1 / (1 - 2/10) = 1.25` times stiffer than
/// Hookean, so the free-draining map's bias is about `+1.25 H dt = +0.25 %`, a fifth of
/// the standard error (0.6 %).
#[test]
fn fene_dumbbell_equilibrium() {
    // H = kT = 1, b = 10: <Q^2> = 3 * 10 / 15 = 2.
    let (h, b) = (1.0, 10.0f64);
    let exact = 3.0 * b / (b + 5.0);
    for (hydro, drift, seed) in [
        (Hydro::FreeDraining, Drift::Uncorrected, 3),
        (Hydro::Rpy, Drift::Midpoint, 4),
    ] {
        let (mut ps, bonds, mut p) = setup(1.4, h, 0.002, hydro, drift, seed);
        p.fene = Some(b.sqrt());
        let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 1));
        let mut ws = buf.workspace();
        let (steps, mut retried) = (1_000_000, 0);
        let mut q2 = Vec::with_capacity(steps);
        for k in 0..steps {
            retried += usize::from(step_or_split(&mut ps, &bonds, &p, &mut ws));
            if k >= 2_000 {
                q2.push((ps.pos[0] - ps.pos[1]).length_squared());
            }
        }
        let (m, se) = block_mean(&q2);
        eprintln!(
            "FENE {hydro:?}: <Q^2> = {m:.4} +- {se:.4}, exact {exact:.4}; {retried} steps retried"
        );
        assert!(se < 0.02 * exact, "too few samples: se {se}");
        assert!(
            (m - exact).abs() < 3.0 * se,
            "{hydro:?}: {m} vs {exact} (se {se})"
        );
        // A Hookean spring of the same H would give 3 kT / H = 3: far outside.
        assert!((3.0 - exact) > 10.0 * se);
    }
}

/// A FENE spring is never stretched to its maximum: a state past it is refused, and a
/// step whose kick would overstretch it is refused with the state and the generator
/// kept, then passes split along the bridge (b = 10 and dt = 0.05: 7 of 20 000 steps
/// at this seed). (With the explicit step a very stiff case, b = 2 at dt = 0.01, can
/// stay refused even as 256 sub-steps: the FENE force's divergence outruns an
/// explicit step near the wall; a semi-implicit FENE step would remove that.)
#[test]
fn fene_refuses_overstretching_and_the_split_step_passes() {
    let q0 = 10f64.sqrt();
    let (mut ps, bonds, mut p) = setup(1.0, 1.0, 0.05, Hydro::FreeDraining, Drift::Midpoint, 8);
    p.fene = Some(q0);
    let mut buf = Buffers::<f64>::new(Layout::for_params(&p, 2, 1));
    let mut ws = buf.workspace();
    let mut refused = 0;
    for _ in 0..20_000 {
        let before = ps.clone();
        if let Err(e) = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            assert!(
                matches!(e, StepError::Bond(BondError::Overstretched { bond: 0, .. })),
                "{e}"
            );
            assert_eq!((ps.pos, ps.time), (before.pos, before.time));
            assert_eq!(ps.noise, before.noise);
            refused += 1;
            assert!(step_or_split(&mut ps, &bonds, &p, &mut ws));
        }
        let q = (ps.pos[0] - ps.pos[1]).length();
        assert!(q < q0, "{q} >= {q0}");
    }
    eprintln!("FENE b = 10, dt = 0.05: {refused} of 20000 steps refused and split");
    assert!(refused > 0);
    // A state already past the maximum is refused.
    ps.pos[1] = DVec3::new(4.0, 0.0, 0.0);
    let e = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap_err();
    assert!(
        matches!(e, StepError::Bond(BondError::Overstretched { bond: 0, .. })),
        "{e}"
    );
}
