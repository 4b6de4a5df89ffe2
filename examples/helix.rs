use glam::DVec3;
use hydrorattle::observables::*;
use hydrorattle::*;
fn helix(dhat: f64, head: f64, rf: f64, pitch: f64, top: bool) -> Vec<(DVec3, f64)> {
    let d = dhat * 2.0;
    let r = rf * d;
    // solve dphi
    let chord = |dp: f64| {
        ((2.0 * r * (dp / 2.0).sin()).powi(2) + (pitch * dp / (2.0 * std::f64::consts::PI)).powi(2))
            .sqrt()
    };
    let (mut lo, mut hi) = (0.0, std::f64::consts::PI);
    for _ in 0..100 {
        let m = 0.5 * (lo + hi);
        if chord(m) < d { lo = m } else { hi = m }
    }
    let dp = 0.5 * (lo + hi);
    let mut v = vec![];
    for k in 0..24 {
        let ph = dp * k as f64;
        let z = pitch * ph / (2.0 * std::f64::consts::PI);
        v.push((
            DVec3::new(r * ph.cos(), r * ph.sin(), if top { -z } else { z }),
            1.0,
        ));
    }
    let dh = dhat * (head + 1.0);
    let dz = (dh * dh - r * r).sqrt();
    let hz = if top { dz } else { -dz };
    v.insert(0, (DVec3::new(0.0, 0.0, hz), head));
    v
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dt: f64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(0.01);
    let tmax: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(200.0);
    let r: f64 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(1.0);
    let pitch: f64 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(3.0);
    let kc: f64 = args.get(5).map(|s| s.parse().unwrap()).unwrap_or(0.0);
    for (name, dhat, head) in [
        ("a", 1.5, 2f64.powf(1.0 / 3.0)),
        ("b", 1.05, 2f64.powf(1.0 / 3.0)),
        ("c", 1.05, 2.0),
    ] {
        let h = helix(dhat, head, r, pitch, false);
        let mut ps: ParticleSet<f64, 32> = ParticleSet::new();
        for (x, a) in &h {
            ps.push(Particle::new(*x, *a, 4.5)).unwrap();
        }
        let mut bonds: BondSet<f64, 32> = BondSet::new();
        for i in 1..25 {
            bonds
                .push(
                    Bond {
                        i: i - 1,
                        j: i,
                        length: dhat * (h[i - 1].1 + h[i].1),
                    },
                    25,
                )
                .unwrap();
        }
        println!(
            "{name}: initial residual {:?} valid {:?}",
            bonds.max_residual(&ps.pos[..25]),
            ps.validate(false)
        );
        let mut p = Params::new(dt);
        p.allow_overlap = true;
        let mut ws: Box<Workspace<f64, 32, 32>> = Box::new(Workspace::new());
        let mut tw: Twist<f64, 32> = Twist::new(0.5);
        tw.update(&ps.pos[..25], p.gravity);
        let steps = (tmax / dt) as usize;
        let t0 = std::time::Instant::now();
        let mut its = 0u64;
        let mut hist = vec![];
        for s in 0..steps {
            let mut contact = |pos: &[DVec3], rad: &[f64], f: &mut [DVec3]| {
                for i in 0..pos.len() {
                    for j in 0..i {
                        let d = pos[i] - pos[j];
                        let s = d.length();
                        let o = rad[i] + rad[j] - s;
                        if o > 0.0 {
                            let ff = d * (kc * o / s);
                            f[i] += ff;
                            f[j] -= ff;
                        }
                    }
                }
            };
            match step(&mut ps, &bonds, &p, &mut ws, &mut contact) {
                Ok(r) => its += r.iterations as u64,
                Err(e) => {
                    println!("err {e} at {s}");
                    break;
                }
            }
            let total = tw.update(&ps.pos[..25], p.gravity);
            if s % (steps / 20) == 0 {
                hist.push((ps.time, total));
                println!(
                    "  t={:7.1} ext={:.3} vert={:.3} twist={:8.3} vhead={:.3} overlap={:?}",
                    ps.time,
                    extension(&ps.pos[..25], bonds.as_slice()),
                    verticality::<f64>(&ps.pos[..25], p.gravity),
                    total,
                    settling_speed::<f64>(&ps.vel[..25], 0, p.gravity),
                    ps.validate(false).err()
                );
            }
        }
        let el = t0.elapsed();
        println!(
            "{name}: {steps} steps in {:?} ({:.2} us/step), mean its {:.2}",
            el,
            el.as_secs_f64() * 1e6 / steps as f64,
            its as f64 / steps as f64
        );
    }
}
