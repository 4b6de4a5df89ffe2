//! The matrix-free mobility (`Params::matrix_free`): no `mu_tt` stored, pair blocks
//! evaluated where they are used. It must give the same bits as the stored path (same
//! pair orientation, same summation order) for every method that offers it and every
//! solver, keep no mobility in its layout, and be refused by the methods that need a
//! stored mobility. At temperature it draws the noise by Lanczos from matrix-free
//! products (the midpoint's product and projection too): the same bits as the stored
//! Lanczos path, no block stored, and a Cholesky factor refused.

use crate::common;

use common::*;
use hydrorattle::{
    BondSet, Brownian, Drift, Layout, Method, NoForce, Noise, NoiseSqrt, ParticleSet, Real,
    SolverKind, StepError, step,
};
use hydrorattle_heap::Buffers;

const N: usize = 40;

fn run_with<T: Real>(method: Method, kind: SolverKind, matrix_free: bool) -> Vec<u64> {
    let scene = helix(N, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, N> = particles(&scene);
    let bonds: BondSet<T, { N - 1 }> = BondSet::chain(&ps.pos[..N]).unwrap();
    let mut p = params::<T>(0.02, method, kind);
    p.matrix_free = matrix_free;
    p.rotation = true; // the spin output is matrix-free in both paths
    let layout = Layout::for_params(&p, N, N - 1);
    if matrix_free {
        assert_eq!(
            layout.blocks, 0,
            "{method:?}: a matrix-free layout stores no blocks"
        );
    }
    let mut store = Buffers::<T>::new(layout);
    let mut ws = store.workspace();
    run(&mut ps, &bonds, &p, &mut ws, &mut NoForce, 10);
    snapshot(&ps)
}

fn same_bits<T: Real>() {
    for method in [Method::Overdamped, Method::Springs] {
        for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
            let stored = run_with::<T>(method, kind, false);
            let free = run_with::<T>(method, kind, true);
            assert_eq!(stored, free, "{method:?} {kind:?}: matrix-free differs");
        }
    }
}

fn refused_where_unsupported<T: Real>() {
    let scene = helix(8, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, 8> = particles(&scene);
    let bonds: BondSet<T, 7> = BondSet::chain(&ps.pos[..8]).unwrap();
    let mut store = Buffers::<T>::new(Layout::all(8, 7));
    let mut ws = store.workspace();
    for method in [Method::Rattle, Method::RattleStable] {
        let mut p = params::<T>(0.02, method, SolverKind::Auto);
        p.matrix_free = true;
        let before = snapshot(&ps);
        let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
        assert!(
            matches!(r, Err(StepError::BadParameter(_))),
            "{method:?}: {r:?}"
        );
        assert_eq!(before, snapshot(&ps));
    }
}

/// Ten thermal steps (kT = 1, Lanczos) of the 40-bead helix: the final state, the
/// generator and the Lanczos iterations of each step.
fn thermal_run<T: Real>(
    method: Method,
    kind: SolverKind,
    drift: Drift,
    matrix_free: bool,
) -> (Vec<u64>, Option<Noise>, Vec<u32>) {
    let scene = helix(N, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, N> = particles(&scene);
    let bonds: BondSet<T, { N - 1 }> = BondSet::chain(&ps.pos[..N]).unwrap();
    let mut p = params::<T>(0.02, method, kind);
    p.matrix_free = matrix_free;
    p.spring_stiffness = T::from_f64(20.0);
    p.brownian = Some(Brownian {
        temperature: T::ONE,
        drift,
    });
    // Auto is Lanczos at every size when matrix-free; the stored path is told.
    p.noise_sqrt = if matrix_free {
        NoiseSqrt::Auto
    } else {
        NoiseSqrt::Lanczos
    };
    let layout = Layout::for_params(&p, N, N - 1);
    if matrix_free {
        assert_eq!(layout.blocks, 0, "{method:?} {drift:?}: blocks stored");
    }
    let mut store = Buffers::<T>::new(layout);
    let mut ws = store.workspace();
    ps.noise = Some(Noise::new(17));
    let its = (0..10)
        .map(|k| {
            let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
            r.unwrap_or_else(|e| panic!("{method:?} {drift:?} step {k}: {e}"))
                .noise_iterations
        })
        .collect();
    (snapshot(&ps), ps.noise.clone(), its)
}

fn thermal_same_bits<T: Real>() {
    let cases = [
        (Method::Overdamped, SolverKind::Krylov),
        (Method::Overdamped, SolverKind::Newton),
        (Method::Springs, SolverKind::Auto),
    ];
    for (method, kind) in cases {
        for drift in [Drift::Midpoint, Drift::Uncorrected] {
            let stored = thermal_run::<T>(method, kind, drift, false);
            let free = thermal_run::<T>(method, kind, drift, true);
            assert!(stored.2.iter().all(|&m| m > 2), "{:?}", stored.2);
            assert_eq!(
                stored, free,
                "{method:?} {kind:?} {drift:?}: matrix-free differs"
            );
        }
    }
}

fn cholesky_noise_refused<T: Real>() {
    let scene = helix(8, 2f64.cbrt(), 3.0, 0.5, 1.5);
    let mut ps: ParticleSet<T, 8> = particles(&scene);
    let bonds: BondSet<T, 7> = BondSet::chain(&ps.pos[..8]).unwrap();
    let mut p = params::<T>(0.02, Method::Overdamped, SolverKind::Auto);
    p.matrix_free = true;
    p.brownian = Some(Brownian::new(T::ONE));
    p.noise_sqrt = NoiseSqrt::Cholesky;
    let mut store = Buffers::<T>::new(Layout::all(8, 7).max(Layout::for_params(&p, 8, 7)));
    let mut ws = store.workspace();
    ps.noise = Some(Noise::new(1));
    let before = snapshot(&ps);
    let r = step(&mut ps, &bonds, &p, &mut ws, &mut NoForce);
    assert!(matches!(r, Err(StepError::Unsupported(_))), "{r:?}");
    assert_eq!(before, snapshot(&ps));
    assert_eq!(ps.noise, Some(Noise::new(1)));
}

both_precisions! {
    matrix_free_thermal_gives_the_stored_lanczos_bits => thermal_same_bits;
    matrix_free_refuses_a_cholesky_noise => cholesky_noise_refused;
    matrix_free_gives_the_stored_bits => same_bits;
    matrix_free_refused_by_methods_that_store => refused_where_unsupported;
}
