mod common;
use common::*;
use hydrorattle::*;

fn diverges<T: Real, const N: usize>(
    spheres: &[Sphere],
    dt: f64,
    steps: usize,
    bound: f64,
) -> (bool, String) {
    let mut ps: ParticleSet<T, N> = particles(spheres);
    let n = ps.len();
    for i in 0..n {
        let k = i as f64;
        ps.vel[i] = v3::<T>(
            0.1 * (1.3 * k).sin(),
            0.1 * (2.1 * k + 0.5).cos(),
            0.1 * (0.7 * k).sin(),
        );
    }
    let bonds: BondSet<T, N> = BondSet::chain(&ps.pos[..n]).unwrap();
    // make velocities consistent? not needed for RATTLE?
    let mut p = params::<T>(dt, Method::Rattle, SolverKind::Newton);
    p.gravity = v3::<T>(0.0, 0.0, 0.0);
    p.allow_overlap = true;
    let mut ws: Box<Workspace<T, N, N>> = Box::new(Workspace::new());
    for k in 0..steps {
        match step(&mut ps, &bonds, &p, &mut ws, &mut NoForce) {
            Err(e) => return (true, format!("err at {k}: {e}")),
            Ok(_) => {
                let vmax = ps.vel[..n]
                    .iter()
                    .map(|&v| norm(f64s::<T>(v)))
                    .fold(0.0, f64::max);
                if vmax > bound {
                    return (true, format!("vmax at {k}"));
                }
            }
        }
    }
    (false, String::new())
}

fn bisect<T: Real, const N: usize>(spheres: &[Sphere], lo: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (lo, hi);
    assert!(!diverges::<T, N>(spheres, lo, 400, 20.0).0);
    assert!(diverges::<T, N>(spheres, hi, 400, 20.0).0);
    while hi / lo > 1.001 {
        let mid = (lo * hi).sqrt();
        let (d, why) = diverges::<T, N>(spheres, mid, 400, 20.0);
        eprintln!("  dt {mid}: {d} {why}");
        if d { hi = mid } else { lo = mid }
    }
    lo
}

fn ex<T: Real>() {
    let lone = [Sphere {
        pos: [0.0; 3],
        radius: 1.0,
        density: RHO,
    }];
    let l = bisect::<T, 1>(&lone, 0.5, 10.0);
    eprintln!("lone: {l}");
    let hel = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    let l = bisect::<T, 25>(&hel, 0.05, 10.0);
    eprintln!("helix: {l}");
    let mut ps: ParticleSet<T, 25> = particles(&hel);
    let bonds: BondSet<T, 25> = BondSet::chain(&ps.pos[..25]).unwrap();
    let mut p = params::<T>(100.0, Method::Rattle, SolverKind::Newton);
    p.stability_guard = true;
    let mut ws: Box<Workspace<T, 25, 25>> = Box::new(Workspace::new());
    eprintln!("{:?}", step(&mut ps, &bonds, &p, &mut ws, &mut NoForce));
    for dt in [0.001, 0.01, 0.1] {
        for kind in [SolverKind::Sweep, SolverKind::Newton] {
            let mut ps: ParticleSet<T, 25> = particles(&hel);
            let mut p = params::<T>(dt, Method::Overdamped, kind);
            p.solver.max_iterations = 10000;
            let r = run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 10);
            eprintln!(
                "dt {dt} {kind:?} {:?}",
                r.iter().map(|r| r.iterations).collect::<Vec<_>>()
            );
        }
    }
}
#[test]
fn ex64() {
    ex::<f64>()
}
#[test]
fn ex32() {
    ex::<f32>()
}
fn ex2<T: Real>() {
    let hel = helix(25, 2f64.powf(1.0 / 3.0), 3.0, 0.5, 1.5);
    for dt in [0.001, 0.01, 0.05, 0.1, 0.3, 0.5, 1.0] {
        eprintln!("dt {dt}: {:?}", diverges::<T, 25>(&hel, dt, 400, 20.0));
    }
}
#[test]
fn ex2_64() {
    ex2::<f64>()
}
