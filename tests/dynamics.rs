mod common;
use common::*;
use hydrorattle::*;

fn dimer_c(a1: f64, a2: f64, d: f64, drho_g: f64, eta: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let w = |a: f64| 4.0 / 3.0 * pi * a * a * a * drho_g;
    let mu = |a: f64| 1.0 / (6.0 * pi * eta * a);
    let big_a = (1.0 + (a1 * a1 + a2 * a2) / (3.0 * d * d)) / (8.0 * pi * eta * d);
    (w(a2) * (mu(a2) - big_a) - w(a1) * (mu(a1) - big_a)) / d
}

fn dimer_theta<T: Real>(method: Method, dt: f64, t_end: f64, st: f64) -> f64 {
    let (a1, a2) = (1.0, 2.0);
    let d = 1.5 * (a1 + a2);
    let (th0, phi) = (2.5f64, 0.7f64);
    let e0 = [th0.sin() * phi.cos(), th0.sin() * phi.sin(), -th0.cos()];
    let spheres = [
        Sphere {
            pos: [0.0; 3],
            radius: a1,
            density: RHO * st,
        },
        Sphere {
            pos: scale(e0, d),
            radius: a2,
            density: RHO * st,
        },
    ];
    let mut ps: ParticleSet<T, 2> = particles(&spheres);
    let bonds: BondSet<T, 1> = BondSet::chain(&ps.pos[..2]).unwrap();
    let mut p = params::<T>(dt, method, SolverKind::Newton);
    p.gravity = v3::<T>(0.0, 0.0, -1.0 / st);
    let mut ws: Workspace<T, 2, 1> = Workspace::new();
    let steps = (t_end / dt).round() as usize;
    run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, steps);
    let e = sub(f64s::<T>(ps.pos[1]), f64s::<T>(ps.pos[0]));
    (e[0].hypot(e[1])).atan2(-e[2])
}

fn explore<T: Real>() {
    let c = dimer_c(1.0, 2.0, 4.5, RHO, 1.0);
    let t_end = 4.0;
    let exact = 2.0 * ((2.5f64 / 2.0).tan() * (-c * t_end).exp()).atan();
    eprintln!("C = {c}, exact theta = {exact}");
    for m in [Method::Overdamped, Method::Overdamped2] {
        for dt in [0.4, 0.2, 0.1, 0.05, 0.025, 0.0125, 0.00625] {
            let th = dimer_theta::<T>(m, dt, t_end, 1.0);
            eprintln!("{m:?} dt {dt} err {:e}", (th - exact).abs());
        }
    }
    for st in [1.0, 0.1, 0.01, 0.001] {
        for dt in [0.01] {
            let th = dimer_theta::<T>(Method::RattleStable, dt, t_end, st);
            let tho = dimer_theta::<T>(Method::Overdamped, dt, t_end, st);
            eprintln!(
                "St {st} dt {dt} err vs exact {:e} vs OD {:e}",
                (th - exact).abs(),
                (th - tho).abs()
            );
        }
    }
}
#[test]
fn ex64() {
    explore::<f64>()
}
#[test]
fn ex32() {
    explore::<f32>()
}
