use hydrorattle::*;
fn main() {
    for method in [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
        Method::Springs,
    ] {
        for rot in [false, true] {
            let mut ps: ParticleSet<f64, 4> = ParticleSet::new();
            ps.push(Particle::new(glam::DVec3::new(0.0, 0.0, 0.0), 1.0, 4.5))
                .unwrap();
            ps.push(Particle::new(glam::DVec3::new(3.0, 0.0, 3.0), 2.0, 4.5))
                .unwrap();
            let bonds: BondSet<f64, 4> = BondSet::chain(&ps.pos[..2]).unwrap();
            let mut p = Params::new(0.01);
            p.method = method;
            p.rotation = rot;
            let mut ws: Workspace<f64, 4, 4> = Workspace::new();
            let mut last = None;
            for _ in 0..1000 {
                last = Some(step(&mut ps, &bonds, &p, &mut ws, &mut NoForce));
                if last.unwrap().is_err() {
                    break;
                }
            }
            let d = ps.pos[1] - ps.pos[0];
            println!(
                "{method:?} rot={rot} {:?} angle={:.4} z={:.4} w={:?}",
                last.unwrap(),
                libm::atan2(d.x, d.z).to_degrees(),
                ps.pos[0].z,
                ps.omega[0]
            );
        }
    }
}
