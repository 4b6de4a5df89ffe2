//! No heap: a counting global allocator shows that assembly, factorisation, solves
//! and whole steps of every method allocate nothing.
//!
//! The allocator wraps `System` and counts calls (alloc, zeroed alloc, realloc and
//! dealloc) made on the current thread while that thread's flag is set. Flag and
//! counter are `const`-initialised thread-locals holding `Cell`s, so touching them never
//! allocates, and tests running in parallel on other threads are not counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::hint::black_box;

use hydrorattle::linalg::{cholesky, cholesky_solve, lu, lu_solve, sym_matvec};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};
use hydrorattle::{
    BondSet, Method, NoForce, Params, Particle, ParticleSet, Real, SolverKind, StepError, step,
};

struct Counting;

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static CALLS: Cell<usize> = const { Cell::new(0) };
}

fn note() {
    // `try_with`: the allocator can run while thread-locals are being torn down.
    let armed = ARMED.try_with(Cell::get).unwrap_or(false);
    if armed {
        let _ = CALLS.try_with(|c| c.set(c.get() + 1));
    }
}

// SAFETY: every call is forwarded unchanged to `System`; counting touches only
// `Cell`s in const-initialised thread-locals, which neither allocate nor re-enter.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        note();
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Runs `f` with counting armed on this thread; returns its result and the number of
/// allocator calls it made.
fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
    CALLS.with(|c| c.set(0));
    ARMED.with(|a| a.set(true));
    let r = f();
    ARMED.with(|a| a.set(false));
    (r, CALLS.with(Cell::get))
}

#[test]
fn positive_control_counts_allocations() {
    let (_, n) = count(|| drop(black_box(Vec::<u64>::with_capacity(16))));
    assert_eq!(n, 2, "one allocation and one deallocation");
    let (_, n) = count(|| {
        let mut v = black_box(Vec::<u8>::new());
        v.extend_from_slice(&[1; 100]);
        v.extend_from_slice(&[2; 1000]);
        black_box(v.len())
    });
    assert!(n >= 2, "growth is counted: {n}");
    let (_, n) = count(|| black_box(1 + 1));
    assert_eq!(n, 0);
}

/// The paper's chain: a head of radius 2^(1/3) then 24 tails of radius 1, bonds of
/// 1.5 (a_i + a_j), laid out along a gently winding helix-like path.
fn chain<T: Real, const N: usize>() -> ParticleSet<T, N> {
    let mut ps = ParticleSet::<T, N>::new();
    let mut at = [0.0f64; 3];
    let mut prev_a = 0.0;
    for k in 0..N {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if k > 0 {
            let t = 0.6 * k as f64;
            let dir = [t.cos(), t.sin(), 0.8];
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            let d = 1.5 * (a + prev_a);
            for c in 0..3 {
                at[c] += dir[c] / len * d;
            }
        }
        let p = Particle::new(T::v3_from(at), T::from_f64(a), T::from_f64(4.5));
        ps.push(p).expect("valid particle");
        prev_a = a;
    }
    ps.validate(false).expect("non-overlapping chain");
    ps
}

fn alloc_free_stages<T: Real>() {
    const N: usize = 25;
    let ps = chain::<T, N>();
    let (pos, rad) = (&ps.pos[..], &ps.radius[..]);
    // Buffers are allocated before counting starts.
    let mut tt = vec![T::M3_ZERO; N * N];
    let mut grand = vec![T::M3_ZERO; 4 * N * N];
    let mut x = vec![T::v3(T::ONE, T::HALF, -T::ONE); 2 * N];
    let mut y = vec![T::V3_ZERO; 2 * N];
    let mut jac: Vec<T> = (0..N * N)
        .map(|k| {
            T::from_f64(
                ((k * 7919) % 101) as f64 / 50.0 - 1.0 + if k % (N + 1) == 0 { 4.0 } else { 0.0 },
            )
        })
        .collect();
    let mut rhs = vec![T::ONE; N];
    let mut piv = vec![0usize; N];
    let (res, n) = count(|| {
        for level in [Hydro::Rpy, Hydro::Oseen, Hydro::FreeDraining] {
            assemble_tt(level, T::ONE, pos, rad, &mut tt)?;
            assemble_grand(level, T::ONE, pos, rad, &mut grand)?;
        }
        Ok::<_, hydrorattle::ParticleError>(())
    });
    res.unwrap();
    assert_eq!(n, 0, "assembly allocated {n} times");
    let (res, n) = count(|| {
        sym_matvec::<T>(&tt, N, &x[..N], &mut y[..N]);
        cholesky::<T>(&mut tt, N)?;
        cholesky_solve::<T>(&tt, N, &mut x[..N]);
        sym_matvec::<T>(&grand, 2 * N, &x, &mut y);
        cholesky::<T>(&mut grand, 2 * N)?;
        cholesky_solve::<T>(&grand, 2 * N, &mut x);
        lu::<T>(&mut jac, N, &mut piv)?;
        lu_solve::<T>(&jac, N, &piv, &mut rhs);
        Ok::<_, hydrorattle::LinalgError>(())
    });
    res.unwrap();
    assert_eq!(n, 0, "linear algebra allocated {n} times");
    // Failures allocate nothing either.
    let mut bad = vec![T::M3_ZERO; 4];
    let (res, n) = count(|| cholesky::<T>(&mut bad, 2));
    assert!(res.is_err());
    assert_eq!(n, 0);
    black_box((&x, &y, &rhs));
}

#[test]
fn assembly_and_factorisation_allocate_nothing_f64() {
    alloc_free_stages::<f64>();
}

#[test]
fn assembly_and_factorisation_allocate_nothing_f32() {
    alloc_free_stages::<f32>();
}

fn alloc_free_steps<T: Real>() {
    const N: usize = 25;
    const B: usize = N - 1;
    let init = chain::<T, N>();
    let bonds = BondSet::<T, B>::chain(&init.pos[..N]).unwrap();
    // The workspace is on the heap, allocated before counting starts.
    let mut ws_store = hydrorattle_heap::Buffers::<T>::new(hydrorattle::Layout::all(N, B));
    let mut ws = ws_store.workspace();
    let methods = [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
        Method::Springs,
    ];
    let mut runs = 0;
    for method in methods {
        for rotation in [false, true] {
            for kind in [SolverKind::Sweep, SolverKind::Newton, SolverKind::Krylov] {
                let mut p = Params::new(T::from_f64(0.01));
                p.method = method;
                p.rotation = rotation;
                p.solver.kind = kind;
                p.solver.max_iterations = 5000;
                let mut ps = init.clone();
                let (res, n) = count(|| {
                    for _ in 0..3 {
                        step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)?;
                    }
                    Ok::<_, StepError>(())
                });
                let tag = format!("{method:?}, rotation {rotation}, {kind:?}");
                res.unwrap_or_else(|e| panic!("{tag}: step failed: {e}"));
                assert_eq!(n, 0, "{tag}: {n} allocator calls in 3 steps");
                assert!(ps.time > init.time);
                runs += 1;
            }
        }
    }
    assert_eq!(runs, 30);
    // Matrix-free: no stored mobility, still no heap.
    for method in [Method::Overdamped, Method::Overdamped2, Method::Springs] {
        let mut p = Params::new(T::from_f64(0.01));
        p.method = method;
        p.matrix_free = true;
        let mut ps = init.clone();
        let (res, n) = count(|| step(&mut ps, &bonds, &p, &mut ws, &mut NoForce));
        res.unwrap_or_else(|e| panic!("{method:?} matrix-free: {e}"));
        assert_eq!(n, 0, "{method:?} matrix-free: {n} allocator calls");
    }
    // A closure force and a failing step (returned error, state untouched) allocate nothing.
    let mut p = Params::new(T::from_f64(0.01));
    p.method = Method::Rattle;
    p.stability_guard = true;
    p.dt = T::from_f64(50.0);
    let mut ps = init.clone();
    let mut push = |_: &[T::V3], _: &[T], f: &mut [T::V3]| f[0] += T::v3(T::ONE, T::ZERO, T::ZERO);
    let (res, n) = count(|| step(&mut ps, &bonds, &p, &mut ws, &mut push));
    assert!(matches!(res, Err(StepError::Unstable { .. })), "{res:?}");
    assert_eq!(n, 0);
    p.dt = T::from_f64(f64::NAN);
    let (res, n) = count(|| step(&mut ps, &bonds, &p, &mut ws, &mut NoForce));
    assert_eq!(res, Err(StepError::BadTimeStep));
    assert_eq!(n, 0);
    assert_eq!(ps.pos, init.pos);
}

#[test]
fn every_step_method_allocates_nothing_f64() {
    alloc_free_steps::<f64>();
}

#[test]
fn every_step_method_allocates_nothing_f32() {
    alloc_free_steps::<f32>();
}

/// `Overdamped2` on the fast free-space product (bonds by Krylov, spins from its grand
/// product) and on PSE in a box: the predictor's and the corrector's products, no heap.
#[cfg(feature = "fast-free")]
#[test]
fn fast_products_overdamped2_allocate_nothing() {
    use hydrorattle::integrate::{fast_storage, fast_vectors, pse_storage};
    const N: usize = 25;
    const B: usize = N - 1;
    let init = chain::<f64, N>();
    let bonds = BondSet::<f64, B>::chain(&init.pos[..N]).unwrap();
    for boxed in [false, true] {
        let mut p = Params::new(0.01);
        p.method = Method::Overdamped2;
        p.solver.kind = SolverKind::Krylov;
        p.matrix_free = true;
        p.pse = Some(1e-5);
        p.rotation = !boxed;
        p.periodic = boxed.then(|| hydrorattle::Periodic::new([60.0; 3]).unwrap());
        let layout = hydrorattle::Layout::for_params(&p, N, B);
        let mut store = hydrorattle_heap::Buffers::<f64>::new(layout);
        let (pos, rad) = (&init.pos[..N], &init.radius[..N]);
        let mut fast = hydrorattle_heap::FreeBuffers::for_step(fast_storage(&p, pos, rad).unwrap());
        let mut pse = hydrorattle_heap::PseBuffers::for_step(pse_storage(&p, rad).unwrap());
        let mut spare = vec![<f64 as Real>::V3_ZERO; fast_vectors(&p, N)];
        let ws = store.workspace();
        let mut ws = match boxed {
            true => pse.attach(ws),
            false => fast.attach(ws).with_fast_vectors(&mut spare),
        };
        let mut ps = init.clone();
        let (res, n) = count(|| {
            for _ in 0..2 {
                step(&mut ps, &bonds, &p, &mut ws, &mut NoForce)?;
            }
            Ok::<_, StepError>(())
        });
        res.unwrap_or_else(|e| panic!("box {boxed}: {e}"));
        assert_eq!(n, 0, "box {boxed}: {n} allocator calls in 2 steps");
        assert!(ps.time > init.time);
    }
}

/// The iterative near field (`Params::near` with `Params::matrix_free`) with bonds: in
/// `Overdamped2` (Krylov, with contacts, Newton) and at temperature, no heap; and on
/// the fast free-space product's grand product (`Params::pse` in free space, the fast
/// arrays the caller's) and on PSE's in a box, in `Overdamped`, `Overdamped2` and at
/// temperature.
#[cfg(feature = "near")]
#[test]
fn iterative_near_field_with_bonds_allocates_nothing() {
    const N: usize = 25;
    const B: usize = N - 1;
    let init = chain::<f64, N>();
    let bonds = BondSet::<f64, B>::chain(&init.pos[..N]).unwrap();
    let mut cases = vec![
        (Method::Overdamped2, SolverKind::Krylov, false, false, None),
        (Method::Overdamped2, SolverKind::Krylov, true, false, None),
        (Method::Overdamped2, SolverKind::Newton, false, false, None),
        (Method::Overdamped, SolverKind::Krylov, false, true, None),
    ];
    if cfg!(feature = "fast-free") {
        let fast = Some(1e-6);
        cases.extend([
            (Method::Overdamped, SolverKind::Krylov, false, false, fast),
            (Method::Overdamped2, SolverKind::Krylov, false, false, fast),
            (Method::Overdamped, SolverKind::Krylov, false, true, fast),
        ]);
    }
    for (method, kind, contacts, thermal, fast) in cases {
        let mut p = Params::new(0.01);
        p.method = method;
        p.solver.kind = kind;
        p.rotation = true;
        p.matrix_free = true;
        p.pse = fast;
        p.near = Some(hydrorattle::stokesian::NearField::default());
        p.contacts = contacts.then(|| hydrorattle::Contacts::new(16));
        p.brownian = thermal.then(|| hydrorattle::Brownian::new(1e-3));
        let layout = hydrorattle::Layout::for_params(&p, N, B);
        let mut store = hydrorattle_heap::Buffers::<f64>::new(layout);
        // The fast product's arrays, where the step takes it (empty otherwise).
        #[cfg(feature = "fast-free")]
        let (mut arrays, mut spare) = {
            use hydrorattle::integrate::{fast_storage, fast_vectors};
            let size = fast_storage(&p, &init.pos[..N], &init.radius[..N]).unwrap();
            let spare = vec![<f64 as Real>::V3_ZERO; fast_vectors(&p, N)];
            (hydrorattle_heap::FreeBuffers::<f64>::for_step(size), spare)
        };
        #[cfg(feature = "fast-free")]
        let mut ws = arrays
            .attach(store.workspace())
            .with_fast_vectors(&mut spare);
        #[cfg(not(feature = "fast-free"))]
        let mut ws = store.workspace();
        let mut ps = init.clone();
        // The generator a thermal step draws from (the others ignore it).
        ps.noise = thermal.then(|| hydrorattle::Noise::new(3));
        let tag =
            format!("{method:?}, {kind:?}, contacts {contacts}, thermal {thermal}, fast {fast:?}");
        two_steps_allocate_nothing(&mut ps, &bonds, &p, &mut ws, &tag);
        assert!(ps.time > init.time, "{tag}");
    }
    // On PSE's grand product in a box (PSE's arrays the caller's, sized by
    // `pse_storage` for the grand product).
    #[cfg(feature = "pse")]
    for (method, thermal) in [
        (Method::Overdamped, false),
        (Method::Overdamped2, false),
        (Method::Overdamped, true),
    ] {
        let mut p = Params::new(0.01);
        p.method = method;
        p.solver.kind = SolverKind::Krylov;
        p.rotation = true;
        p.matrix_free = true;
        p.pse = Some(1e-4);
        p.periodic = Some(hydrorattle::Periodic::new([64.0; 3]).unwrap());
        p.near = Some(hydrorattle::stokesian::NearField::default());
        p.brownian = thermal.then(|| hydrorattle::Brownian::new(1e-3));
        let layout = hydrorattle::Layout::for_params(&p, N, B);
        let mut store = hydrorattle_heap::Buffers::<f64>::new(layout);
        let size = hydrorattle::integrate::pse_storage(&p, &init.radius[..N]).unwrap();
        let mut arrays = hydrorattle_heap::PseBuffers::<f64>::for_step(size);
        let mut ws = arrays.attach(store.workspace());
        let mut ps = init.clone();
        ps.noise = thermal.then(|| hydrorattle::Noise::new(3));
        let tag = format!("PSE in a box, {method:?}, thermal {thermal}");
        two_steps_allocate_nothing(&mut ps, &bonds, &p, &mut ws, &tag);
        assert!(ps.time > init.time, "{tag}");
    }
}

/// Two steps of `ps` under `p` succeed without an allocator call (`tag` names them).
#[cfg(feature = "near")]
fn two_steps_allocate_nothing<const N: usize, const B: usize>(
    ps: &mut ParticleSet<f64, N>,
    bonds: &BondSet<f64, B>,
    p: &Params<f64>,
    ws: &mut hydrorattle::Workspace<'_, f64>,
    tag: &str,
) {
    let (res, n) = count(|| {
        for _ in 0..2 {
            step(ps, bonds, p, ws, &mut NoForce)?;
        }
        Ok::<_, StepError>(())
    });
    res.unwrap_or_else(|e| panic!("{tag}: {e}"));
    assert_eq!(n, 0, "{tag}: {n} allocator calls in 2 steps");
}
