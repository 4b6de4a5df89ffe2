//! Physics validation of the integrators: the settling dimer against its
//! closed form, constraints on chains, rings and trees, flows, rotation, and the
//! sweep-versus-Newton iteration counts on the paper's helix.
//!
//! Units: eta = 1, |g| = 1, density 4.5, so a lone unit sphere settles at speed 1 and
//! relaxes its momentum in time 1 (Stokes number St = 2/9 rho a U0 / eta = 1).

use crate::common;

use common::*;
use hydrorattle::{BondSet, Hydro, Method, NoForce, ParticleSet, Real, SolverKind, step};
use std::f64::consts::PI;

const CONSTRAINED: [Method; 4] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
];
const KINDS: [SolverKind; 2] = [SolverKind::Sweep, SolverKind::Newton];

// ---------------------------------------------------------------------------------
// 1. The settling dimer.
// ---------------------------------------------------------------------------------

/// Rotation rate `C` of a rigid dimer settling in the far-field RPY approximation.
///
/// Spheres 1 (radius `a1`) and 2 (radius `a2`), centres `d > a1 + a2` apart, unit bond
/// vector `e = (r2 - r1) / d`, gravity direction `g` (unit), buoyant weights
/// `W_k = 4/3 pi a_k^3 (rho - rho_f) |g|`. The forces are `F_1 = W_1 g - T e` and
/// `F_2 = W_2 g + T e` with `T` the bond tension (the constraint acts only along `e`).
///
/// RPY, far branch: `mu_kk = I / (6 pi eta a_k)`, and the pair block
/// `mu_12 = A I + B e e` with `A = (1 + (a1^2 + a2^2) / (3 d^2)) / (8 pi eta d)` and
/// `B = (1 - (a1^2 + a2^2) / d^2) / (8 pi eta d)`.
///
/// `U_1 = mu_11 F_1 + mu_12 F_2`, `U_2 = mu_12 F_1 + mu_22 F_2`. Every term along `e`
/// (the tension, and the `B e e` part) drops out of the relative velocity's component
/// perpendicular to the bond; with `g_perp = g - (g.e) e`:
///
/// `(U_2 - U_1)_perp = [W_2 (mu_2 - A) - W_1 (mu_1 - A)] g_perp`,  `mu_k = 1/(6 pi eta a_k)`.
///
/// The bond direction then obeys `de/dt = (U_2 - U_1)_perp / d`. With `theta` the angle
/// between `e` and `g` (`cos theta = e.g`), `|g_perp| = sin theta` and `g_perp` points
/// towards `g`, so `d theta / dt = -C sin theta` with
///
/// `C = [W_2 (mu_2 - A) - W_1 (mu_1 - A)] / d`,
///
/// whose solution is `tan(theta/2) = tan(theta0/2) exp(-C t)`: the sphere with the
/// larger Stokes velocity (`W_k mu_k = 2/9 (rho - rho_f) |g| a_k^2 / eta`) turns
/// head-down. `e` stays in the vertical plane it starts in.
fn dimer_rate(a1: f64, a2: f64, d: f64, drho_g: f64, eta: f64) -> f64 {
    assert!(d > a1 + a2, "far-field branch only");
    let weight = |a: f64| 4.0 / 3.0 * PI * a.powi(3) * drho_g;
    let mu = |a: f64| 1.0 / (6.0 * PI * eta * a);
    let big_a = (1.0 + (a1 * a1 + a2 * a2) / (3.0 * d * d)) / (8.0 * PI * eta * d);
    (weight(a2) * (mu(a2) - big_a) - weight(a1) * (mu(a1) - big_a)) / d
}

/// The dimer of the tests: radii 1 and 2, `d = 1.5 (a1 + a2) = 4.5`, equal density
/// `4.5 st`, gravity `1/st` (same weights for every Stokes number `st`).
struct Dimer {
    theta0: f64,
    phi: f64,
    st: f64,
}

impl Dimer {
    const A1: f64 = 1.0;
    const A2: f64 = 2.0;
    const D: f64 = 4.5;

    fn rate() -> f64 {
        dimer_rate(Self::A1, Self::A2, Self::D, RHO, 1.0)
    }

    fn exact_theta(&self, t: f64) -> f64 {
        2.0 * ((self.theta0 / 2.0).tan() * (-Self::rate() * t).exp()).atan()
    }

    /// `(theta, phi)` of the bond after `t_end / dt` steps (bond from small to big).
    fn run<T: Real>(&self, method: Method, dt: f64, t_end: f64) -> (f64, f64) {
        let (th, ph) = (self.theta0, self.phi);
        // theta is measured from g = -z: e = (sin th cos ph, sin th sin ph, -cos th).
        let e0 = [th.sin() * ph.cos(), th.sin() * ph.sin(), -th.cos()];
        let spheres = [
            Sphere {
                pos: [0.5, -0.25, 1.0],
                radius: Self::A1,
                density: RHO * self.st,
            },
            Sphere {
                pos: add([0.5, -0.25, 1.0], scale(e0, Self::D)),
                radius: Self::A2,
                density: RHO * self.st,
            },
        ];
        let mut ps: ParticleSet<T, 2> = particles(&spheres);
        let bonds: BondSet<T, 1> = BondSet::chain(&ps.pos[..2]).unwrap();
        let mut p = params::<T>(dt, method, SolverKind::Newton);
        p.gravity = v3::<T>(0.0, 0.0, -1.0 / self.st);
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
        let mut ws = ws_store.workspace();
        let steps = (t_end / dt).round() as usize;
        run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
        let e = sub(f64s::<T>(ps.pos[1]), f64s::<T>(ps.pos[0]));
        (e[0].hypot(e[1]).atan2(-e[2]), e[1].atan2(e[0]))
    }
}

const DIMER: Dimer = Dimer {
    theta0: 2.5,
    phi: 0.7,
    st: 1.0,
};
const T_END: f64 = 4.0;

/// The instantaneous turning rate of the first step is `-C sin(theta0)`.
fn dimer_initial_rate<T: Real>() {
    let c = Dimer::rate();
    let dt = pick::<T>(1e-3, 1e-5);
    let (theta, _) = DIMER.run::<T>(Method::Overdamped, dt, dt);
    let measured = (theta - DIMER.theta0) / dt;
    let want = -c * DIMER.theta0.sin();
    let rel = (measured / want - 1.0).abs();
    eprintln!(
        "dimer C = {c:.12}; first-step rate {measured:.9} vs -C sin(theta0) {want:.9} (rel {rel:.1e})"
    );
    assert!(rel < pick::<T>(1e-2, 1e-4), "rate {measured} vs {want}");
}

/// Overdamped (order 1) and Overdamped2 (order 2) converge to the closed form.
fn dimer_convergence<T: Real>() {
    let exact = DIMER.exact_theta(T_END);
    let dts = [0.2, 0.1, 0.05, 0.025];
    for (method, lo, hi, finest) in [
        (Method::Overdamped, 0.8, 1.3, 3e-3),
        (Method::Overdamped2, 1.7, 2.4, 5e-5),
    ] {
        let mut errors = Vec::new();
        for &dt in &dts {
            let (theta, phi) = DIMER.run::<T>(method, dt, T_END);
            errors.push((theta - exact).abs());
            // The bond stays in its initial vertical plane.
            let plane = pick::<T>(1e-5, 1e-12);
            assert!(
                (phi - DIMER.phi).abs() < plane,
                "{method:?} dt {dt}: phi {phi}"
            );
        }
        let order = loglog_slope(&dts, &errors);
        eprintln!(
            "dimer {method:?}: theta({T_END}) exact {exact:.9}; errors {} at dt {dts:?}; order {order:.3}",
            sci(&errors)
        );
        assert!((lo..=hi).contains(&order), "{method:?} order {order}");
        assert!(errors[3] < finest, "{method:?} error {:e}", errors[3]);
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "{method:?} {errors:?}"
        );
    }
}

/// RattleStable approaches the overdamped solution as St -> 0, linearly in St.
fn dimer_stokes_limit<T: Real>() {
    let dt = 0.01;
    let exact = DIMER.exact_theta(T_END);
    let mut gaps = Vec::new();
    for st in [0.1, 0.01, 0.001] {
        let dimer = Dimer { st, ..DIMER };
        let (inertial, _) = dimer.run::<T>(Method::RattleStable, dt, T_END);
        let (overdamped, _) = dimer.run::<T>(Method::Overdamped, dt, T_END);
        let gap = (inertial - overdamped).abs();
        eprintln!(
            "dimer St {st}: |RattleStable - Overdamped| = {gap:.3e}, |RattleStable - exact| = {:.3e}",
            (inertial - exact).abs()
        );
        gaps.push(gap);
    }
    for w in gaps.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (5.0..20.0).contains(&ratio),
            "gap not ~linear in St: {gaps:?}"
        );
    }
    // Vanishing mass: the implicit-drag step is the overdamped step.
    let st = pick::<T>(1e-6, 1e-10);
    let dimer = Dimer { st, ..DIMER };
    let (inertial, _) = dimer.run::<T>(Method::RattleStable, 0.05, T_END);
    let (overdamped, _) = dimer.run::<T>(Method::Overdamped, 0.05, T_END);
    let gap = (inertial - overdamped).abs();
    eprintln!("dimer St {st:e}: |RattleStable - Overdamped| = {gap:.3e}");
    assert!(gap < pick::<T>(2e-4, 1e-8), "gap {gap:e}");
}

/// An independent reference for the inertial dimer (St = 1, no closed form): the
/// constrained equations of motion written out and integrated by classical RK4 at a
/// small step, in `f64`, with the two-sphere RPY mobility assembled here.
///
/// `m_k a_k = F_k - (R (v - 0))_k + F^C_k`, `R = mu^-1` (6x6), `F^C_1 = lambda g`,
/// `F^C_2 = -lambda g`, `g = r_1 - r_2`; `lambda` from the second derivative of the
/// constraint, `g.(a_1 - a_2) + |v_1 - v_2|^2 = 0`.
mod inertial_reference {
    use super::common::*;
    use std::f64::consts::PI;

    type State = [[f64; 3]; 4]; // r1, r2, v1, v2

    /// Inverse of a 6x6 matrix by Gauss-Jordan with partial pivoting.
    fn invert(mut a: [[f64; 6]; 6]) -> [[f64; 6]; 6] {
        let mut inv = [[0.0; 6]; 6];
        for (i, row) in inv.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        for c in 0..6 {
            let p = (c..6)
                .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                .unwrap();
            a.swap(c, p);
            inv.swap(c, p);
            let d = a[c][c];
            for k in 0..6 {
                a[c][k] /= d;
                inv[c][k] /= d;
            }
            for r in 0..6 {
                if r != c {
                    let f = a[r][c];
                    for k in 0..6 {
                        a[r][k] -= f * a[c][k];
                        inv[r][k] -= f * inv[c][k];
                    }
                }
            }
        }
        inv
    }

    fn mobility(r1: [f64; 3], r2: [f64; 3], a1: f64, a2: f64) -> [[f64; 6]; 6] {
        let g = sub(r1, r2);
        let s = norm(g);
        let e = scale(g, 1.0 / s);
        let q = (a1 * a1 + a2 * a2) / (s * s);
        let (ca, cb) = ((1.0 + q / 3.0) / (8.0 * PI * s), (1.0 - q) / (8.0 * PI * s));
        let mut m = [[0.0; 6]; 6];
        for i in 0..3 {
            m[i][i] = 1.0 / (6.0 * PI * a1);
            m[3 + i][3 + i] = 1.0 / (6.0 * PI * a2);
            for j in 0..3 {
                let pair = if i == j { ca } else { 0.0 } + cb * e[i] * e[j];
                m[i][3 + j] = pair;
                m[3 + i][j] = pair;
            }
        }
        m
    }

    fn rate(x: &State, radii: [f64; 2], masses: [f64; 2], weights: [f64; 2]) -> State {
        let [r1, r2, v1, v2] = *x;
        let res = invert(mobility(r1, r2, radii[0], radii[1]));
        let v = [v1[0], v1[1], v1[2], v2[0], v2[1], v2[2]];
        let mut acc = [[0.0; 3]; 2];
        for k in 0..2 {
            for c in 0..3 {
                let drag: f64 = (0..6).map(|j| res[3 * k + c][j] * v[j]).sum();
                let weight = if c == 2 { -weights[k] } else { 0.0 };
                acc[k][c] = (weight - drag) / masses[k];
            }
        }
        let g = sub(r1, r2);
        let v12 = sub(v1, v2);
        let lambda = -(dot(g, sub(acc[0], acc[1])) + dot(v12, v12))
            / (dot(g, g) * (1.0 / masses[0] + 1.0 / masses[1]));
        let a1 = add(acc[0], scale(g, lambda / masses[0]));
        let a2 = sub(acc[1], scale(g, lambda / masses[1]));
        [v1, v2, a1, a2]
    }

    /// `(theta, phi)` of the bond at `t_end` from rest at `(theta0, phi)`.
    pub fn theta(theta0: f64, phi: f64, t_end: f64, dt: f64) -> f64 {
        let (a1, a2, d) = (1.0, 2.0, 4.5);
        let vol = |a: f64| 4.0 / 3.0 * PI * a.powi(3);
        let masses = [vol(a1) * RHO, vol(a2) * RHO];
        let e0 = [
            theta0.sin() * phi.cos(),
            theta0.sin() * phi.sin(),
            -theta0.cos(),
        ];
        let mut x: State = [[0.0; 3], scale(e0, d), [0.0; 3], [0.0; 3]];
        let f = |x: &State| rate(x, [a1, a2], masses, masses);
        let axpy = |x: &State, k: &State, h: f64| -> State {
            core::array::from_fn(|i| add(x[i], scale(k[i], h)))
        };
        for _ in 0..(t_end / dt).round() as usize {
            let k1 = f(&x);
            let k2 = f(&axpy(&x, &k1, dt / 2.0));
            let k3 = f(&axpy(&x, &k2, dt / 2.0));
            let k4 = f(&axpy(&x, &k3, dt));
            x = core::array::from_fn(|i| {
                let s = add(add(k1[i], scale(k2[i], 2.0)), add(scale(k3[i], 2.0), k4[i]));
                add(x[i], scale(s, dt / 6.0))
            });
        }
        let e = sub(x[1], x[0]);
        e[0].hypot(e[1]).atan2(-e[2])
    }
}

/// The inertial schemes (St = 1) converge to the independent RK4 reference, at first
/// order: the paper's velocity update `v* = v + a(t) dt + a_C dt / 2` uses the
/// acceleration at `t` only, and the stable scheme is backward Euler in the velocity.
fn dimer_inertial<T: Real>() {
    let reference = inertial_reference::theta(DIMER.theta0, DIMER.phi, T_END, 1e-3);
    let check = inertial_reference::theta(DIMER.theta0, DIMER.phi, T_END, 5e-4);
    assert!((reference - check).abs() < 1e-10, "reference not converged");
    let dts = [0.1, 0.05, 0.025, 0.0125];
    for method in [Method::Rattle, Method::RattleStable] {
        let errors: Vec<f64> = dts
            .iter()
            .map(|&dt| (DIMER.run::<T>(method, dt, T_END).0 - reference).abs())
            .collect();
        let order = loglog_slope(&dts, &errors);
        eprintln!(
            "inertial dimer St 1 {method:?}: theta({T_END}) reference {reference:.9}; errors {} at dt {dts:?}; order {order:.2}",
            sci(&errors)
        );
        assert!((0.8..=1.3).contains(&order), "{method:?} order {order}");
        assert!(errors[3] < 0.01, "{method:?} errors {errors:?}");
    }
}

both_precisions! {
    dimer_inertial_schemes_converge => dimer_inertial;
    dimer_initial_rate_matches_closed_form => dimer_initial_rate;
    dimer_overdamped_orders => dimer_convergence;
    dimer_rattle_stable_stokes_limit => dimer_stokes_limit;
}

// ---------------------------------------------------------------------------------
// 2. Constraints hold on chains, rings and trees; constraint forces are internal.
// ---------------------------------------------------------------------------------

/// Every constrained method, both solvers, three topologies: the bond residual is
/// within tolerance after every step, and RATTLE leaves velocities tangent to bonds.
fn bonds_hold<T: Real>() {
    let tol = Real::to_f64(
        params::<T>(0.05, Method::Overdamped, SolverKind::Newton)
            .solver
            .tolerance,
    );
    let slack = tol + 16.0 * T::EPSILON.to_f64();
    for scene in [chain_scene(), ring_scene(), tree_scene()] {
        for method in CONSTRAINED {
            for kind in KINDS {
                let (mut ps, bonds) = scene.build::<T, 8, 8>();
                let start = f64s::<T>(ps.pos[0]);
                let p = params::<T>(0.05, method, kind);
                let mut ws_store =
                    hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
                let mut ws = ws_store.workspace();
                let (mut worst, mut worst_rate) = (0.0f64, 0.0f64);
                for k in 0..40 {
                    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap_or_else(|e| {
                        panic!("{} {method:?} {kind:?} step {k}: {e}", scene.name)
                    });
                    let err = bond_error(&ps, &bonds);
                    assert!(
                        err <= slack && r.residual.to_f64() <= slack,
                        "{} {method:?} {kind:?} step {k}: bond error {err:e} (report {:e})",
                        scene.name,
                        r.residual.to_f64()
                    );
                    worst = worst.max(err);
                    if matches!(method, Method::Rattle | Method::RattleStable) {
                        let rate = bond_rate_error(&ps, &bonds, 0.05);
                        assert!(
                            rate <= slack,
                            "{} {method:?} {kind:?} step {k}: (r_i-r_j).(v_i-v_j) residual {rate:e}",
                            scene.name
                        );
                        worst_rate = worst_rate.max(rate);
                    }
                }
                // The scene really moved (it settles by about one radius per unit time).
                let moved = norm(sub(f64s::<T>(ps.pos[0]), start));
                assert!(moved > 0.2, "{} {method:?}: moved only {moved}", scene.name);
                eprintln!(
                    "{:5} {method:?} {kind:?}: max bond error {worst:.1e}, max rate error {worst_rate:.1e}",
                    scene.name
                );
            }
        }
    }
}

/// Free-draining momentum balance: the constraint forces are equal and opposite, so
/// summed over beads they cancel and the drag balances the external forces alone.
/// Overdamped schemes: `sum zeta_i v_i' = sum F_i`; implicit drag:
/// `sum [m_i (v_i' - v_i)/dt + zeta_i v_i'] = sum F_i`; explicit drag:
/// `sum [m_i (v_i' - v_i)/dt + zeta_i v_i] = sum F_i` (`zeta_i = 6 pi eta a_i`).
fn constraint_forces_internal<T: Real>() {
    let dt = 0.05;
    let pull = [5.0, -2.0, 1.0];
    for scene in [chain_scene(), ring_scene(), tree_scene()] {
        for method in CONSTRAINED {
            let (mut ps, bonds) = scene.build::<T, 8, 8>();
            let n = ps.len();
            let mut p = params::<T>(dt, method, SolverKind::Newton);
            p.hydro = Hydro::FreeDraining;
            let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
            let mut ws = ws_store.workspace();
            // Gravity plus a pull on bead 0 through the force hook.
            let mut hook = |_: &[T::V3], _: &[T], f: &mut [T::V3]| {
                f[0] += T::v3_from(pull);
            };
            let mut total = pull;
            for s in &scene.spheres {
                total[2] -= 4.0 / 3.0 * PI * s.radius.powi(3) * s.density;
            }
            for k in 0..20 {
                let old_vel: Vec<[f64; 3]> = ps.vel[..n].iter().map(|&v| f64s::<T>(v)).collect();
                step(&mut ps, &bonds, &p, &mut ws, &mut hook)
                    .unwrap_or_else(|e| panic!("{} {method:?} step {k}: {e}", scene.name));
                let mut balance = [0.0; 3];
                for (i, &old) in old_vel.iter().enumerate() {
                    let a = ps.radius[i].to_f64();
                    let zeta = 6.0 * PI * a;
                    let mass = 4.0 / 3.0 * PI * a.powi(3) * ps.density[i].to_f64();
                    let v = f64s::<T>(ps.vel[i]);
                    let term = match method {
                        Method::Overdamped | Method::Overdamped2 => scale(v, zeta),
                        Method::RattleStable => add(scale(sub(v, old), mass / dt), scale(v, zeta)),
                        _ => add(scale(sub(v, old), mass / dt), scale(old, zeta)),
                    };
                    balance = add(balance, term);
                }
                let err = norm(sub(balance, total)) / norm(total);
                // f32: velocities come from position differences (cancellation).
                assert!(
                    err < pick::<T>(2e-3, 1e-9),
                    "{} {method:?} step {k}: momentum balance off by {err:e}",
                    scene.name
                );
            }
        }
    }
}

/// Constraint forces do no net work: with `F_C = lambda_l g_l` on `i` (and `-` on `j`),
/// the work per step `sum_l lambda_l g_l.(dr_i - dr_j)` is `O(dt^2)` because the bond
/// length is kept (`g.dr_ij = -|dr_ij|^2/2` exactly on the constraint), so its share of
/// the gravitational work over a fixed time vanishes linearly with `dt`.
fn constraint_work_vanishes<T: Real>() {
    let t_end = 1.0;
    let dts = [0.1, 0.05, 0.025];
    let mut ratios = Vec::new();
    for &dt in &dts {
        let (mut ps, bonds) = tree_scene().build::<T, 8, 8>();
        let n = ps.len();
        let p = params::<T>(dt, Method::Overdamped, SolverKind::Newton);
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
        let mut ws = ws_store.workspace();
        let (mut w_c, mut w_g) = (0.0f64, 0.0f64);
        for _ in 0..(t_end / dt).round() as usize {
            let old: Vec<[f64; 3]> = ps.pos[..n].iter().map(|&v| f64s::<T>(v)).collect();
            step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
            let lambda = ws.multipliers(bonds.len());
            for (l, b) in bonds.as_slice().iter().enumerate() {
                let g = sub(old[b.i], old[b.j]);
                let dr = sub(
                    sub(f64s::<T>(ps.pos[b.i]), old[b.i]),
                    sub(f64s::<T>(ps.pos[b.j]), old[b.j]),
                );
                w_c += lambda[l].to_f64() * dot(g, dr);
            }
            for (i, r0) in old.iter().enumerate() {
                let a = ps.radius[i].to_f64();
                let weight = 4.0 / 3.0 * PI * a.powi(3) * ps.density[i].to_f64();
                w_g += -weight * (f64s::<T>(ps.pos[i])[2] - r0[2]);
            }
        }
        ratios.push((w_c / w_g).abs());
    }
    let order = loglog_slope(&dts, &ratios);
    eprintln!(
        "constraint work / gravity work: {} at dt {dts:?} (order {order:.2})",
        sci(&ratios)
    );
    assert!(ratios[2] < 0.05, "{ratios:?}");
    assert!((0.8..1.3).contains(&order), "order {order}");
}

both_precisions! {
    bonds_hold_all_methods_topologies_solvers => bonds_hold;
    constraint_forces_are_internal => constraint_forces_internal;
    constraint_work_vanishes_with_dt => constraint_work_vanishes;
}

// ---------------------------------------------------------------------------------
// 3. Flows: uniform flow carries force-free beads; a rigid rotation of the fluid
//    rotates a chain rigidly.
// ---------------------------------------------------------------------------------

/// Gravity off, uniform flow `V`: every bead moves with `V`, the chain is unchanged.
/// Inertial methods start at the flow velocity (the drag then vanishes identically).
fn uniform_flow<T: Real>() {
    let flow = [0.3, -0.2, 0.5];
    let (dt, steps) = (0.05, 20);
    let t = dt * steps as f64;
    for method in CONSTRAINED {
        for kind in KINDS {
            let (mut ps, bonds) = chain_scene().build::<T, 8, 8>();
            let n = ps.len();
            for v in &mut ps.vel[..n] {
                *v = T::v3_from(flow);
            }
            let start: Vec<[f64; 3]> = ps.pos[..n].iter().map(|&v| f64s::<T>(v)).collect();
            let mut p = params::<T>(dt, method, kind);
            p.gravity = T::V3_ZERO;
            p.flow_velocity = T::v3_from(flow);
            let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
            let mut ws = ws_store.workspace();
            run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
            let tol = pick::<T>(2e-5, 1e-12);
            for (i, &r0) in start.iter().enumerate() {
                let want = add(r0, scale(flow, t));
                let got = f64s::<T>(ps.pos[i]);
                let dv = norm(sub(f64s::<T>(ps.vel[i]), flow));
                assert!(
                    norm(sub(got, want)) < tol * 10.0 && dv < tol,
                    "{method:?} {kind:?} bead {i}: pos {got:?} want {want:?}, velocity off by {dv:e}"
                );
            }
            assert!(bond_error(&ps, &bonds) < tol, "{method:?}: chain deformed");
        }
    }
}

/// Largest distance between the beads and their initial positions rotated by
/// `|Omega| t` about `Omega` (through the origin).
fn rotation_error<T: Real, const N: usize>(
    ps: &ParticleSet<T, N>,
    start: &[[f64; 3]],
    omega: [f64; 3],
    t: f64,
) -> f64 {
    let w = norm(omega);
    let axis = scale(omega, 1.0 / w);
    start
        .iter()
        .enumerate()
        .map(|(i, &r0)| norm(sub(f64s::<T>(ps.pos[i]), rotate(r0, axis, w * t))))
        .fold(0.0, f64::max)
}

/// Gravity off, fluid in rigid rotation `U = Omega x r`: torque- and force-free spheres
/// feel no disturbance (a rigid rotation has no strain), so the chain turns rigidly
/// about the origin. First-order error for Overdamped, second for Overdamped2.
fn rigid_rotation<T: Real>() {
    let omega = [0.2, -0.1, 0.4];
    let t_end = 2.0;
    let dts = [0.1, 0.05, 0.025];
    for (method, lo, hi) in [
        (Method::Overdamped, 0.8, 1.3),
        (Method::Overdamped2, 1.7, 2.4),
    ] {
        let mut errors = Vec::new();
        for &dt in &dts {
            let (mut ps, bonds) = chain_scene().build::<T, 8, 8>();
            let n = ps.len();
            let start: Vec<[f64; 3]> = ps.pos[..n].iter().map(|&v| f64s::<T>(v)).collect();
            let mut p = params::<T>(dt, method, SolverKind::Newton);
            p.gravity = T::V3_ZERO;
            p.vorticity = T::v3_from(omega);
            let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(8, 8));
            let mut ws = ws_store.workspace();
            let steps = (t_end / dt).round() as usize;
            run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
            errors.push(rotation_error(&ps, &start, omega, t_end));
            // Every pair distance is kept, not only the bonded ones: a rigid motion.
            for i in 0..n {
                for j in 0..i {
                    let d0 = norm(sub(start[i], start[j]));
                    let d1 = norm(sub(f64s::<T>(ps.pos[i]), f64s::<T>(ps.pos[j])));
                    assert!(
                        (d1 - d0).abs() < 0.05 * d0 * dt / 0.1,
                        "{method:?} dt {dt}: pair {i}-{j} {d0} -> {d1}"
                    );
                }
            }
        }
        let order = loglog_slope(&dts, &errors);
        let angle = norm(omega) * t_end;
        eprintln!(
            "rigid rotation {method:?} (angle {angle:.3} rad): errors {} at dt {dts:?}, order {order:.2}",
            sci(&errors)
        );
        assert!((lo..=hi).contains(&order), "{method:?} order {order}");
        assert!(errors[2] < 0.05, "{method:?} errors {errors:?}");
    }
}

both_precisions! {
    uniform_flow_carries_beads => uniform_flow;
    rigid_fluid_rotation_rotates_chain => rigid_rotation;
}

// ---------------------------------------------------------------------------------
// 9. Rotation resolved.
// ---------------------------------------------------------------------------------

/// A lone sphere at the origin of a rigidly rotating fluid, rotational inertia
/// `I = 2/5 m a^2`, rotational drag `8 pi eta a^3`: `I dW/dt = 8 pi eta a^3 (Omega - W)`.
/// The implicit (backward Euler) drag gives `W_n = Omega (1 - q^n)`,
/// `q = tau_r / (tau_r + dt)`, `tau_r = I / (8 pi eta a^3)`; `W -> Omega`.
fn spin_up<T: Real>() {
    let omega = [0.3, -0.2, 0.5];
    let (a, dt) = (1.2, 0.05);
    let mut ps: ParticleSet<T, 1> = particles(&[Sphere {
        pos: [0.0; 3],
        radius: a,
        density: RHO,
    }]);
    let bonds: BondSet<T, 1> = BondSet::new();
    let mut p = params::<T>(dt, Method::RattleStable, SolverKind::Newton);
    p.rotation = true;
    p.gravity = T::V3_ZERO;
    p.vorticity = T::v3_from(omega);
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(1, 1));
    let mut ws = ws_store.workspace();
    let mass = 4.0 / 3.0 * PI * a.powi(3) * RHO;
    let tau_r = 0.4 * mass * a * a / (8.0 * PI * a.powi(3));
    let q = tau_r / (tau_r + dt);
    let tol = pick::<T>(1e-5, 1e-12);
    for k in 1..=200 {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
        let want = scale(omega, 1.0 - q.powi(k));
        let got = f64s::<T>(ps.omega[0]);
        assert!(
            norm(sub(got, want)) < tol * norm(omega),
            "step {k}: W = {got:?}, want {want:?}"
        );
        // The continuous solution, to O(dt / tau_r).
        let cont = scale(omega, 1.0 - (-(k as f64) * dt / tau_r).exp());
        assert!(
            norm(sub(got, cont)) < 0.1 * norm(omega),
            "step {k}: far from exp relaxation"
        );
        assert!(norm(f64s::<T>(ps.pos[0])) < tol && norm(f64s::<T>(ps.vel[0])) < tol);
    }
    let end = norm(sub(f64s::<T>(ps.omega[0]), omega)) / norm(omega);
    eprintln!(
        "spin-up: tau_r = {tau_r}, |W - Omega| / |Omega| after {:.1} tau_r = {end:.1e}",
        200.0 * dt / tau_r
    );
    assert!(end < pick::<T>(1e-5, 1e-9));
}

/// Two spheres settling side by side, at `+x` (sphere 0) and `-x` (sphere 1), `s` apart.
/// The angular velocity of a torque-free sphere is half the vorticity of the flow
/// the other one drives; for a Stokeslet `u = (F + (F.e) e) / (8 pi eta r)` that is
/// `W_i = (F_j x e) / (8 pi eta s^2)` with `e = (r_i - r_j) / s` (the RPY rt block in the
/// far field). With `F = -W g z`: `F_1 x (+x) = -W_1 y`, so sphere 0 (on the +x side) spins
/// about `-y`, sphere 1 about `+y`: each rolls "towards" the other's wake, the faces
/// looking at each other moving down faster. A bond along `e` adds forces parallel to
/// `e` which do not contribute.
fn side_by_side<T: Real>() {
    let cases: [(&str, f64, f64, f64, bool); 2] = [
        ("equal, free", 1.0, 1.0, 4.0, false),
        ("unequal, bonded", 1.0, 1.5, 1.5 * 2.5, true),
    ];
    for (name, a0, a1, s, bonded) in cases {
        for method in [Method::Overdamped, Method::Overdamped2] {
            let mut ps: ParticleSet<T, 2> = particles(&[
                Sphere {
                    pos: [s / 2.0, 0.0, 0.0],
                    radius: a0,
                    density: RHO,
                },
                Sphere {
                    pos: [-s / 2.0, 0.0, 0.0],
                    radius: a1,
                    density: RHO,
                },
            ]);
            let bonds: BondSet<T, 1> = if bonded {
                BondSet::chain(&ps.pos[..2]).unwrap()
            } else {
                BondSet::new()
            };
            let mut p = params::<T>(0.1, method, SolverKind::Newton);
            p.rotation = true;
            let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
            let mut ws = ws_store.workspace();
            step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
            let weight = |a: f64| 4.0 / 3.0 * PI * a.powi(3) * RHO;
            let c = 1.0 / (8.0 * PI * s * s);
            let want0 = [0.0, -weight(a1) * c, 0.0];
            let want1 = [0.0, weight(a0) * c, 0.0];
            let tol = pick::<T>(1e-5, 1e-12);
            for (i, want) in [(0, want0), (1, want1)] {
                let got = f64s::<T>(ps.omega[i]);
                assert!(
                    norm(sub(got, want)) < tol * norm(want),
                    "{name} {method:?} sphere {i}: W = {got:?}, want {want:?}"
                );
            }
            eprintln!(
                "side by side ({name}, {method:?}): W0 = {:?}, W1 = {:?}",
                f64s::<T>(ps.omega[0]),
                f64s::<T>(ps.omega[1])
            );
        }
    }
    // Equal free spheres keep falling side by side, so W is steady; the inertial
    // schemes relax to the same value (the explicit one reports the spin driven by the
    // drag force R (v - U), which equals the weight at terminal velocity).
    for method in [Method::RattleStable, Method::Rattle] {
        let mut ps: ParticleSet<T, 2> = particles(&[
            Sphere {
                pos: [2.0, 0.0, 0.0],
                radius: 1.0,
                density: RHO,
            },
            Sphere {
                pos: [-2.0, 0.0, 0.0],
                radius: 1.0,
                density: RHO,
            },
        ]);
        let bonds: BondSet<T, 1> = BondSet::new();
        let mut p = params::<T>(0.1, method, SolverKind::Newton);
        p.rotation = true;
        let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
        let mut ws = ws_store.workspace();
        run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 300);
        let want = 6.0 * PI / (8.0 * PI * 16.0);
        let got0 = f64s::<T>(ps.omega[0]);
        let got1 = f64s::<T>(ps.omega[1]);
        eprintln!(
            "side by side ({method:?}, t = 30): W0 = {got0:?}, W1 = {got1:?}, want -/+ {want}"
        );
        let tol = pick::<T>(1e-4, 1e-8);
        assert!(
            norm(sub(got0, [0.0, -want, 0.0])) < tol * want,
            "{method:?} W0 {got0:?}"
        );
        assert!(
            norm(sub(got1, [0.0, want, 0.0])) < tol * want,
            "{method:?} W1 {got1:?}"
        );
    }
}

/// With rotation resolved, the implicit-drag step on the grand mobility reduces to the
/// overdamped one as masses and moments of inertia vanish: same positions, and the
/// angular velocities `W = mu_rt (F + F_C)` the overdamped step reports.
fn rotation_massless_limit<T: Real>() {
    let st = pick::<T>(1e-6, 1e-10);
    let spheres = [
        Sphere {
            pos: [0.0; 3],
            radius: 1.0,
            density: RHO * st,
        },
        Sphere {
            pos: [3.0, 0.5, 2.5],
            radius: 2.0,
            density: RHO * st,
        },
    ];
    let mut inertial: ParticleSet<T, 2> = particles(&spheres);
    let mut overdamped = inertial.clone();
    let bonds: BondSet<T, 1> = BondSet::chain(&inertial.pos[..2]).unwrap();
    let mut p = params::<T>(0.05, Method::RattleStable, SolverKind::Newton);
    p.rotation = true;
    p.gravity = v3::<T>(0.0, 0.0, -1.0 / st);
    p.vorticity = v3::<T>(0.0, 0.1, 0.0);
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(2, 1));
    let mut ws = ws_store.workspace();
    run(&mut inertial, &bonds, &p, &mut ws, &mut NoForce, 20);
    p.method = Method::Overdamped;
    run(&mut overdamped, &bonds, &p, &mut ws, &mut NoForce, 20);
    for i in 0..2 {
        let dr = norm(sub(
            f64s::<T>(inertial.pos[i]),
            f64s::<T>(overdamped.pos[i]),
        ));
        let w = f64s::<T>(overdamped.omega[i]);
        let dw = norm(sub(f64s::<T>(inertial.omega[i]), w)) / norm(w);
        assert!(
            dr < pick::<T>(1e-3, 1e-6),
            "sphere {i}: positions differ by {dr:e}"
        );
        assert!(
            dw < pick::<T>(1e-3, 1e-6),
            "sphere {i}: W {w:?} differs by relative {dw:e}"
        );
    }
}

both_precisions! {
    rotation_rattle_stable_massless_limit => rotation_massless_limit;
    lone_sphere_spins_up_to_vorticity => spin_up;
    side_by_side_spheres_counter_rotate => side_by_side;
}

// ---------------------------------------------------------------------------------
// 8. Sweeps versus Newton on the paper's 25-bead helix.
// ---------------------------------------------------------------------------------

fn sweep_vs_newton<T: Real>() {
    let scene = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let steps = 10;
    for dt in [0.001, 0.01, 0.1] {
        let mut mean = [0.0f64; 2];
        let mut ends: Vec<Vec<[f64; 3]>> = Vec::new();
        for (slot, kind) in KINDS.into_iter().enumerate() {
            let mut ps: ParticleSet<T, 25> = particles(&scene);
            let bonds: BondSet<T, 24> = BondSet::chain(&ps.pos[..25]).unwrap();
            let mut p = params::<T>(dt, Method::Overdamped, kind);
            p.solver.max_iterations = 1000;
            let mut ws_store =
                hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(25, 24));
            let mut ws = ws_store.workspace();
            let reports = run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
            let its: Vec<u32> = reports.iter().map(|r| r.iterations).collect();
            mean[slot] = its.iter().map(|&i| f64::from(i)).sum::<f64>() / steps as f64;
            eprintln!(
                "helix {} dt {dt}: {kind:?} iterations per step {its:?} (mean {:.1})",
                if is_single::<T>() { "f32" } else { "f64" },
                mean[slot]
            );
            assert!(
                its.iter().all(|&i| i >= 1),
                "{kind:?}: the unconstrained move must need correcting"
            );
            ends.push(ps.pos[..25].iter().map(|&v| f64s::<T>(v)).collect());
        }
        // Both solve the same equations to the same tolerance.
        let gap = ends[0]
            .iter()
            .zip(&ends[1])
            .map(|(a, b)| norm(sub(*a, *b)))
            .fold(0.0, f64::max);
        assert!(
            gap < pick::<T>(1e-3, 1e-7),
            "dt {dt}: sweep and Newton differ by {gap:e}"
        );
        if dt == 0.1 {
            assert!(
                mean[1] <= mean[0],
                "Newton {} vs sweeps {}",
                mean[1],
                mean[0]
            );
        }
    }
}

both_precisions! {
    helix_sweep_versus_newton_iterations => sweep_vs_newton;
}
