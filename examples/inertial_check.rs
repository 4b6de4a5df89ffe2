use glam::DVec3;
use hydrorattle::*;
fn run(method: Method, dt: f64, hydro: Hydro, n: usize, t_end: f64) -> Vec<DVec3> {
    let st = 0.1;
    let mut ps: ParticleSet<f64, 8> = ParticleSet::new();
    for k in 0..n {
        ps.push(Particle::new(
            DVec3::new(3.0 * k as f64, 0.0, 1.5 * k as f64 * (k % 2) as f64),
            1.0 + 0.3 * k as f64,
            4.5 * st,
        ))
        .unwrap();
    }
    let bonds: BondSet<f64, 8> = BondSet::chain(&ps.pos[..n]).unwrap();
    let mut p = Params::new(dt);
    p.method = method;
    p.hydro = hydro;
    p.gravity = DVec3::new(0.0, 0.0, -1.0 / st);
    p.solver.tolerance = 1e-13;
    let mut ws: Box<Workspace<f64, 8, 8>> = Box::new(Workspace::new());
    let steps = (t_end / dt).round() as usize;
    for _ in 0..steps {
        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce).unwrap();
    }
    ps.pos[..n].to_vec()
}
fn err(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared())
        .sum::<f64>()
        / a.len() as f64)
        .sqrt()
}
fn main() {
    for hydro in [Hydro::FreeDraining, Hydro::Rpy] {
        for n in [1, 2, 3] {
            let r = run(Method::Rattle, 0.0002, hydro, n, 1.0);
            let rs = run(Method::RattleStable, 0.0002, hydro, n, 1.0);
            print!(
                "{hydro:?} n={n}: paper vs stable at dt=2e-4: {:.2e};",
                err(&r, &rs)
            );
            for dt in [0.004, 0.002, 0.001] {
                print!(
                    " dt={dt}: paper {:.2e} stable {:.2e};",
                    err(&run(Method::Rattle, dt, hydro, n, 1.0), &r),
                    err(&run(Method::RattleStable, dt, hydro, n, 1.0), &r)
                );
            }
            println!();
        }
    }
}
