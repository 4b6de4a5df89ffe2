//! The lane batch (`hydrorattle_parallel::batch`) against the kernel's own `f64` step:
//! every system of a batch must have, after every step, the bits it has when stepped
//! alone (the reference is the kernel's scalar path, which the repository validates
//! against closed forms elsewhere); diverging decisions and failed lanes must fall
//! back, and systems of different shapes be refused.

#[path = "common/helix25.rs"]
mod helix25;

use hydrorattle::glam::DVec3;
use hydrorattle::{Layout, NoForce, Params, ParticleError, ParticleSet, StepError, StepReport};
use hydrorattle_heap::Buffers;
use hydrorattle_parallel::batch::{Batch, BatchError, Counts, Forces, LV3, Lanes};

use helix25::N;

type Set = ParticleSet<f64, N>;

/// Steps `sets` alone and in a batch `steps` times, comparing every system's positions,
/// velocities and time bit for bit after every step, and the results (reports or
/// errors). Returns the batch's counts.
fn compare<const K: usize>(
    sets: [Set; K],
    params: [&Params<f64>; K],
    steps: usize,
    force: &mut impl Forces<K>,
) -> Counts {
    let bonds = helix25::bonds(helix25::HEAD_RATIO);
    compare_with(sets, [&bonds[..]; K], params, steps, force)
}

/// [`compare`] with each system's own bonds.
fn compare_with<const K: usize>(
    sets: [Set; K],
    bonds: [&[hydrorattle::Bond<f64>]; K],
    params: [&Params<f64>; K],
    steps: usize,
    force: &mut impl Forces<K>,
) -> Counts {
    let mut batch = Batch::<K>::new(N, bonds, params).expect("batch");
    let layout = Layout::for_params(params[0], N, bonds[0].len());
    let mut lanes = Buffers::<Lanes<K>>::new(layout);
    let mut one = Buffers::<f64>::new(layout);
    let mut alone_ws = Buffers::<f64>::new(layout);
    let mut batched = sets.clone();
    let mut alone = sets;
    for step in 0..steps {
        let got = batch
            .step(
                batched.each_mut().map(|s| s.state()),
                &mut lanes.workspace(),
                &mut one.workspace(),
                force,
            )
            .expect("same shapes");
        for k in 0..K {
            let mut add = |p: &[DVec3], r: &[f64], f: &mut [DVec3]| force.system(k, p, r, f);
            let want = hydrorattle::step_slices(
                alone[k].state(),
                bonds[k],
                params[k],
                &mut alone_ws.workspace(),
                &mut add,
            );
            assert!(
                same(&got[k], &want),
                "step {step}, system {k}: {:?} against {want:?}",
                got[k]
            );
            let bits = |s: &Set| {
                let v = |x: &[DVec3]| {
                    x.iter()
                        .flat_map(|v| v.to_array().map(f64::to_bits))
                        .collect::<Vec<_>>()
                };
                (v(&s.pos[..N]), v(&s.vel[..N]), s.time.to_bits())
            };
            assert!(
                bits(&batched[k]) == bits(&alone[k]),
                "step {step}, system {k}: bits differ"
            );
        }
    }
    batch.counts()
}

/// The same report (residual and tension by their bits) or the same error.
fn same(a: &Result<StepReport<f64>, StepError>, b: &Result<StepReport<f64>, StepError>) -> bool {
    match (a, b) {
        (Ok(a), Ok(b)) => {
            let bits = |r: &StepReport<f64>| {
                let mut r = *r;
                let t = (r.residual.to_bits(), r.max_tension.to_bits());
                (r.residual, r.max_tension) = (0.0, 0.0);
                (r, t)
            };
            bits(a) == bits(b)
        }
        (Err(a), Err(b)) => a == b,
        _ => false,
    }
}

/// Tilts spread over a quarter turn.
fn tilts<const K: usize>() -> [f64; K] {
    core::array::from_fn(|k| 0.3 * k as f64 / K as f64 + 0.05)
}

/// (a) The tilt sweep at K = 2, 4 and 8: every lane keeps its own bits at every step,
/// and most steps stay in the lanes (the method works on the sweep it is for).
#[test]
fn tilt_sweep_keeps_each_systems_bits() {
    fn run<const K: usize>() {
        let p = helix25::params();
        let sets = tilts::<K>().map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
        let c = compare::<K>(sets, [&p; K], 2000, &mut NoForce);
        assert_eq!((c.lane_steps, c.failed), (2000, 0));
        // Most system steps in the lanes (the measured rates are in
        // docs/BENCHMARKS.md).
        assert!(c.fallback_rate(K) < 0.5, "K = {K}: {c:?}");
    }
    run::<2>();
    run::<4>();
    run::<8>();
}

/// Per-system parameters: each lane its own gravity (the helix tilted is the same as
/// gravity turned) and its own time step, real values only.
#[test]
fn per_system_gravity_and_time_step() {
    let base = helix25::params();
    let ps: [Params<f64>; 4] = core::array::from_fn(|k| {
        let mut p = base;
        let a = 0.1 * k as f64;
        p.gravity = DVec3::new(0.0, libm::sin(a), -libm::cos(a));
        p.dt = 0.01 * (1.0 + 0.01 * k as f64);
        p
    });
    let sets = [0.0; 4].map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
    let c = compare::<4>(sets, ps.each_ref(), 500, &mut NoForce);
    assert!(c.fallback_rate(4) < 0.5, "{c:?}");
}

/// Per-system bonds: heads of different sizes (bond lengths differ by lane).
#[test]
fn per_system_head_ratio() {
    let p = helix25::params();
    let heads = [1.2, 1.26, 1.3, 1.35];
    let bonds = heads.map(helix25::bonds);
    let sets = heads.map(|h| helix25::beads(0.05, 4.5, h));
    let c = compare_with::<4>(
        sets,
        bonds.each_ref().map(|b| &b[..]),
        [&p; 4],
        300,
        &mut NoForce,
    );
    assert!(c.lane_steps == 300 && c.failed == 0, "{c:?}");
}

/// (b) Systems unlike enough that their Newton iterations differ (densities 1 to 10:
/// the sinking speed, so the constraint drift each step, differs tenfold): the
/// divergence is detected, those steps fall back, and the bits are still each
/// system's own.
#[test]
fn divergence_falls_back_with_the_same_bits() {
    let p = helix25::params();
    let sets = [1.0, 10.0, 2.0, 7.0].map(|rho| helix25::beads(0.1, rho, helix25::HEAD_RATIO));
    let c = compare::<4>(sets, [&p; 4], 300, &mut NoForce);
    assert!(c.diverged > 0 && c.failed == 0, "{c:?}");
    // Only the lanes that left lane 0's path are redone.
    assert!(
        c.fallback_steps >= c.diverged && c.fallback_steps <= 3 * c.diverged,
        "{c:?}"
    );
}

/// A force that pushes one system's bead 7 sideways, hard: that system's chain bends
/// away from the others' (a decision diverges), and the force reaches the right lane
/// on both paths.
struct Kick {
    lane: usize,
    size: f64,
}

impl<const K: usize> Forces<K> for Kick {
    fn lanes(&mut self, _: &[LV3<K>], _: &[Lanes<K>], force: &mut [LV3<K>]) {
        force[7].x.0[self.lane] += self.size;
    }
    fn system(&mut self, k: usize, _: &[DVec3], _: &[f64], force: &mut [DVec3]) {
        if k == self.lane {
            force[7].x += self.size;
        }
    }
}

#[test]
fn a_force_on_one_lane() {
    let p = helix25::params();
    let sets = [0.0; 4].map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
    let mut kick = Kick {
        lane: 2,
        size: 50.0,
    };
    let c = compare::<4>(sets, [&p; 4], 200, &mut kick);
    assert!(c.lane_steps == 200 && c.failed == 0, "{c:?}");
}

/// (c) One system with a NaN position: it gets the kernel's own error with its state
/// unchanged, the others advance with their own bits (`compare` checks both against
/// the systems stepped alone), and the next steps go on the same way.
#[test]
fn a_bad_lane_gets_its_error_the_others_advance() {
    let p = helix25::params();
    let mut sets = tilts::<4>().map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
    sets[1].pos[3].y = f64::NAN;
    let before = sets[1].pos;
    let bonds = helix25::bonds(helix25::HEAD_RATIO);
    let mut batch = Batch::<4>::uniform(N, &bonds, &p).unwrap();
    let layout = Layout::for_params(&p, N, bonds.len());
    let (mut lanes, mut one) = (Buffers::new(layout), Buffers::new(layout));
    let got = batch
        .step(
            sets.each_mut().map(|s| s.state()),
            &mut lanes.workspace(),
            &mut one.workspace(),
            &mut NoForce,
        )
        .unwrap();
    assert_eq!(
        got[1],
        Err(StepError::Particle(ParticleError::NonFinite {
            particle: 3
        }))
    );
    assert!(
        sets[1]
            .pos
            .iter()
            .zip(&before)
            .all(|(a, b)| a.to_array().map(f64::to_bits) == b.to_array().map(f64::to_bits))
    );
    assert!(got[0].is_ok() && got[2].is_ok() && got[3].is_ok());
    // Bit for bit against each system alone, over further steps.
    let mut fresh = tilts::<4>().map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
    fresh[1].pos[3].y = f64::NAN;
    let c = compare::<4>(fresh, [&p; 4], 50, &mut NoForce);
    // Lane 1's checks diverge from lane 0's: lane 1 alone is redone, every step.
    assert_eq!((c.lane_steps, c.failed, c.fallback_steps), (50, 0, 50));
}

/// A bad parameter in one system (a negative time step): that system's own error.
#[test]
fn a_bad_parameter_in_one_system() {
    let good = helix25::params();
    let mut bad = good;
    bad.dt = -0.01;
    let sets = [0.0; 4].map(|t| helix25::beads(t, 4.5, helix25::HEAD_RATIO));
    let c = compare::<4>(sets, [&good, &good, &good, &bad], 20, &mut NoForce);
    assert_eq!(c.fallback_steps, 20, "{c:?}");
}

/// (d) Systems of different shapes are refused, naming the first that differs.
#[test]
fn mismatched_systems_are_refused() {
    let p = helix25::params();
    let bonds = helix25::bonds(helix25::HEAD_RATIO);
    // Different bond topology.
    let mut other = bonds.clone();
    other[3].j = 5;
    assert_eq!(
        Batch::<2>::new(N, [&bonds, &other[..]], [&p, &p]).unwrap_err(),
        BatchError::Bonds { system: 1 }
    );
    assert_eq!(
        Batch::<3>::new(N, [&bonds, &bonds, &bonds[1..]], [&p; 3]).unwrap_err(),
        BatchError::Bonds { system: 2 }
    );
    // Different control parameters (a real value alone may differ).
    let mut q = p;
    q.solver.max_iterations = 49;
    assert_eq!(
        Batch::<2>::new(N, [&bonds; 2], [&p, &q]).unwrap_err(),
        BatchError::Params { system: 1 }
    );
    let mut q = p;
    q.solver.tolerance = 1e-11;
    assert!(Batch::<2>::new(N, [&bonds; 2], [&p, &q]).is_ok());
    let mut q = p;
    q.fene = Some(4.0);
    assert_eq!(
        Batch::<2>::new(N, [&bonds; 2], [&p, &q]).unwrap_err(),
        BatchError::Params { system: 1 }
    );
    // Thermal noise.
    let mut q = p;
    q.brownian = Some(hydrorattle::Brownian::new(0.1));
    assert!(matches!(
        Batch::<2>::uniform(N, &bonds, &q),
        Err(BatchError::Unsupported(_))
    ));
    // A system with another number of spheres: refused, nothing stepped.
    let mut batch = Batch::<2>::uniform(N, &bonds, &p).unwrap();
    let mut a = helix25::beads(0.0, 4.5, helix25::HEAD_RATIO);
    let mut b: ParticleSet<f64, 30> = ParticleSet::new();
    for i in 0..24 {
        b.push(hydrorattle::Particle::new(a.pos[i], a.radius[i], 4.5))
            .unwrap();
    }
    let start = a.pos;
    let layout = Layout::for_params(&p, N, bonds.len());
    let (mut lanes, mut one) = (Buffers::new(layout), Buffers::new(layout));
    let r = batch.step(
        [a.state(), b.state()],
        &mut lanes.workspace(),
        &mut one.workspace(),
        &mut NoForce,
    );
    assert_eq!(
        r.unwrap_err(),
        BatchError::Length {
            system: 1,
            len: 24,
            expected: N
        }
    );
    assert!(a.pos == start);
    assert_eq!(batch.counts(), Counts::default());
}
