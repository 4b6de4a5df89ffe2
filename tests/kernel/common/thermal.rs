//! Helpers of the Brownian tests (`tests/kernel/brownian.rs`, `tests/kernel/inertial_thermal.rs`,
//! `tests/kernel/weak_order.rs`, `tests/kernel/periodic_brownian.rs`): thermal parameters, a sampling
//! loop, block standard errors, a freely jointed chain and the retried step.

use super::{params, step_thermal};
use hydrorattle::glam::DVec3;
use hydrorattle::{
    BondSet, Brownian, Drift, Hydro, Layout, Method, NoForce, Noise, Params, Particle, ParticleSet,
    Real, SolverKind, Workspace, step,
};
use hydrorattle_heap::Buffers;

/// Thermal parameters: no gravity, `kT = 1`, the given drift and hydrodynamics.
pub fn thermal<T: Real>(dt: f64, eta: f64, hydro: Hydro, drift: Drift) -> Params<T> {
    let mut p = params::<T>(dt, Method::Overdamped, SolverKind::Auto);
    p.viscosity = T::from_f64(eta);
    p.gravity = T::V3_ZERO;
    p.hydro = hydro;
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    p
}

/// `steps` thermal steps from `ps`, calling `observe` after each.
pub fn sample<T: Real, const N: usize, const B: usize>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    seed: u64,
    steps: usize,
    mut observe: impl FnMut(&ParticleSet<T, N>),
) {
    let mut buf = Buffers::<T>::new(Layout::for_params(p, ps.len(), bonds.len()));
    let mut ws = buf.workspace();
    let mut noise = Noise::new(seed);
    for k in 0..steps {
        step_thermal(ps, bonds, p, &mut ws, &mut NoForce, &mut noise)
            .unwrap_or_else(|e| panic!("step {k}: {e}"));
        observe(ps);
    }
}

/// Mean of `x` and its standard error from `blocks` equal block means (the blocks
/// absorb time correlation shorter than a block).
pub fn block_mean(x: &[f64], blocks: usize) -> (f64, f64) {
    let len = x.len() / blocks;
    let means: Vec<f64> = x
        .chunks_exact(len)
        .map(|c| c.iter().sum::<f64>() / len as f64)
        .collect();
    mean_se(&means)
}

/// Mean and standard error of independent samples.
pub fn mean_se(x: &[f64]) -> (f64, f64) {
    let k = x.len() as f64;
    let m = x.iter().sum::<f64>() / k;
    let var = x.iter().map(|b| (b - m) * (b - m)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

/// A freely jointed chain of `n` unit spheres (density 0), bonds of length `b` in a
/// zigzag (right angles in alternating planes), with its bonds at those lengths.
pub fn zigzag_chain<const N: usize, const B: usize>(
    n: usize,
    b: f64,
) -> (ParticleSet<f64, N>, BondSet<f64, B>) {
    let mut ps = ParticleSet::<f64, N>::new();
    let mut r = DVec3::ZERO;
    for k in 0..n {
        ps.push(Particle::new(r, 1.0, 0.0)).unwrap();
        r += match k % 3 {
            0 => DVec3::X,
            1 => DVec3::Y,
            _ => DVec3::Z,
        } * b;
    }
    let bonds = BondSet::chain(&ps.pos[..n]).unwrap();
    (ps, bonds)
}

/// One step with the set's own generator; a refused step (no root of the projection
/// near the start) is retried as 2, 4, ... 64 sub-steps along the Brownian bridge, as
/// host-demo retries it. Returns whether it was retried; panics if no split succeeds.
pub fn step_retrying<const N: usize, const B: usize>(
    ps: &mut ParticleSet<f64, N>,
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ws: &mut Workspace<'_, f64>,
) -> bool {
    let Err(e) = step(ps, bonds, p, ws, &mut NoForce) else {
        return false;
    };
    let (start, base) = (ps.clone(), ps.noise.clone().unwrap());
    let done = (1..=6u8).any(|depth| {
        let mut q = *p;
        q.dt = p.dt / f64::from(1u32 << depth);
        let ok = (0..1u32 << depth).all(|index| {
            ps.noise = Some(base.split(depth, index));
            step(ps, bonds, &q, ws, &mut NoForce).is_ok()
        });
        if ok {
            ps.noise = ps.noise.take().map(Noise::join);
        } else {
            *ps = start.clone();
        }
        ok
    });
    assert!(done, "no split of the step succeeded: {e}");
    true
}

/// Mean and standard error of `run(seed)` over the independent seeds `0..seeds`, half
/// of them on each of two threads (each run's result one sample).
pub fn over_seeds(seeds: u64, run: impl Fn(u64) -> f64 + Sync) -> (f64, f64) {
    let run = &run;
    let per: Vec<f64> = std::thread::scope(|s| {
        let handles: Vec<_> = [0..seeds / 2, seeds / 2..seeds]
            .into_iter()
            .map(|r| s.spawn(move || r.map(run).collect::<Vec<f64>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    mean_se(&per)
}

/// `E[h - h0 | h > h0]` for the height density `exp(-(h - h0)) / mu_perp(h)` (`kT = 1`,
/// unit weight): the equilibrium of a Brownian step above a wall that leaves out the drift
/// `kT d(mu_perp)/dh`; midpoint rule on `[h0, h0 + 40]` with `nodes` nodes.
pub fn biased_mean(h0: f64, nodes: usize, mu_perp: impl Fn(f64) -> f64) -> f64 {
    let dh = 40.0 / nodes as f64;
    let (mut z, mut m) = (0.0, 0.0);
    for k in 0..nodes {
        let y = (k as f64 + 0.5) * dh;
        let w = (-y).exp() / mu_perp(h0 + y);
        z += w;
        m += w * y;
    }
    m / z
}
