//! Thermal noise through the C interface: the temperature, the drift
//! and a generator (seed, save by copy, restore by copy). A run through the interface
//! is the kernel's run bit for bit; a refused step leaves the generator as it was; a
//! restored generator continues the same run.

use core::ptr::null_mut;

use hydrorattle_ffi::*;
use kernel::glam::DVec3;

const N: usize = 3;

/// A bent trimer (radius 1, bonds 3) at kT = 0.5, RPY, midpoint drift.
struct Run {
    pos: [[f64; 3]; N],
    vel: [[f64; 3]; N],
    omega: [[f64; 3]; N],
    radius: [f64; N],
    density: [f64; N],
    bonds: [HrBondF64; 2],
    time: f64,
    noise: HrNoise,
    storage: Vec<u64>,
}

fn params(drift: HrDrift) -> HrParamsF64 {
    let mut p = hr_params_default_f64(0.01);
    p.gravity = [0.0; 3];
    p.temperature = 0.5;
    p.drift = drift as u32;
    p
}

fn start(seed: u64, p: &HrParamsF64) -> Run {
    let bytes = unsafe { hr_storage_bytes_f64(p, N, 2) };
    assert!(bytes > 0);
    Run {
        pos: [[0.0; 3], [3.0, 0.0, 0.0], [3.0, 3.0, 0.0]],
        vel: [[0.0; 3]; N],
        omega: [[0.0; 3]; N],
        radius: [1.0; N],
        density: [4.5; N],
        bonds: [
            HrBond {
                i: 0,
                j: 1,
                length: 3.0,
            },
            HrBond {
                i: 1,
                j: 2,
                length: 3.0,
            },
        ],
        time: 0.0,
        noise: hr_noise_seed(seed),
        storage: vec![0; bytes.div_ceil(8)],
    }
}

fn step(r: &mut Run, p: &HrParamsF64) -> HrStatus {
    let mut st = HrState {
        n: N,
        pos: r.pos.as_mut_ptr(),
        vel: r.vel.as_mut_ptr(),
        omega: r.omega.as_mut_ptr(),
        radius: r.radius.as_ptr(),
        density: r.density.as_ptr(),
        time: r.time,
        noise: &mut r.noise,
    };
    let bytes = r.storage.len() * 8;
    let s = unsafe {
        hr_step_f64(
            &mut st,
            r.bonds.as_ptr(),
            2,
            p,
            r.storage.as_mut_ptr().cast(),
            bytes,
            None,
            null_mut(),
            null_mut(),
        )
    };
    r.time = st.time;
    s
}

/// 200 steps through the interface equal 200 steps of the kernel's own front door with
/// the same seed (both drifts), bit for bit: the interface converts, nothing more.
#[test]
fn the_interface_runs_the_kernel_s_brownian_steps() {
    for (drift, kdrift) in [
        (HrDrift::Midpoint, kernel::Drift::Midpoint),
        (HrDrift::Uncorrected, kernel::Drift::Uncorrected),
    ] {
        let p = params(drift);
        let mut c = start(11, &p);
        for k in 0..200 {
            assert_eq!(step(&mut c, &p), HrStatus::Ok, "step {k}");
        }
        let mut ps = kernel::ParticleSet::<f64, N>::new();
        for r in [[0.0; 3], [3.0, 0.0, 0.0], [3.0, 3.0, 0.0]] {
            ps.push(kernel::Particle::new(DVec3::from(r), 1.0, 4.5))
                .unwrap();
        }
        let mut bonds = kernel::BondSet::<f64, 2>::new();
        bonds
            .push(
                kernel::Bond {
                    i: 0,
                    j: 1,
                    length: 3.0,
                },
                N,
            )
            .unwrap();
        bonds
            .push(
                kernel::Bond {
                    i: 1,
                    j: 2,
                    length: 3.0,
                },
                N,
            )
            .unwrap();
        let mut kp = kernel::Params::new(0.01);
        kp.gravity = DVec3::ZERO;
        kp.brownian = Some(kernel::Brownian {
            temperature: 0.5,
            drift: kdrift,
        });
        ps.noise = Some(kernel::Noise::new(11));
        let layout = kernel::Layout::for_params(&kp, N, 2);
        let mut blocks = vec![kernel::glam::DMat3::ZERO; layout.blocks];
        let mut vectors = vec![DVec3::ZERO; layout.vectors];
        let mut scalars = vec![0.0f64; layout.scalars];
        let mut indices = vec![0usize; layout.indices];
        let mut ws = kernel::Workspace::new(&mut blocks, &mut vectors, &mut scalars, &mut indices);
        for _ in 0..200 {
            kernel::step(&mut ps, &bonds, &kp, &mut ws, &mut kernel::NoForce).unwrap();
        }
        for i in 0..N {
            assert_eq!(c.pos[i], ps.pos[i].to_array(), "{drift:?}: bead {i}");
        }
        assert_eq!(c.noise.words, ps.noise.unwrap().save());
    }
}

/// A copy of the generator and the state taken after 50 steps, put back after 100,
/// continues to the same bits; a refused step (one sweep cannot converge) leaves
/// the generator as it was; words no generator has are refused.
#[test]
fn a_saved_generator_restores_the_run_and_a_refused_step_keeps_it() {
    let p = params(HrDrift::Midpoint);
    let mut r = start(5, &p);
    for _ in 0..50 {
        assert_eq!(step(&mut r, &p), HrStatus::Ok);
    }
    let (pos, time, saved) = (r.pos, r.time, r.noise);
    for _ in 0..100 {
        assert_eq!(step(&mut r, &p), HrStatus::Ok);
    }
    let end = r.pos;
    (r.pos, r.time, r.noise) = (pos, time, saved);
    for _ in 0..100 {
        assert_eq!(step(&mut r, &p), HrStatus::Ok);
    }
    assert_eq!(r.pos, end);
    assert_ne!(r.noise, saved);

    let mut q = p;
    q.solver = HrSolver::Sweep as u32;
    q.max_iterations = 1;
    let (before, pos) = (r.noise, r.pos);
    assert_eq!(step(&mut r, &q), HrStatus::NoConvergence);
    assert_eq!((r.noise, r.pos), (before, pos));

    r.noise = HrNoise { words: [0; 6] };
    assert_eq!(step(&mut r, &p), HrStatus::BadParameter);
    assert_eq!(r.noise.words, [0; 6]);
}
