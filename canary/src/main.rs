//! No-std, no-alloc canary: links the hydrorattle kernel into a freestanding binary.
//!
//! If the kernel (or anything it depends on) pulled in `std` or `alloc`, this would
//! fail to build: for `thumbv7em-none-eabihf` there is no `std` to link, and on the
//! host our `#[panic_handler]` would clash with `std`'s.
//!
//! The entry point builds a 4-bead chain on the stack (starting from a `static`
//! empty set, so a whole state can live in a `static`), assembles the translational
//! and grand RPY mobilities, factorises both, solves with the factors and runs a full
//! `step()` of every method in `f32` and `f64`. `black_box` keeps it all alive.
//!
//! On x86_64 Linux the binary can be run: exit status 0 when every stage succeeded,
//! 1 when one returned an error, 101 on panic. On Cortex-M it parks in a loop.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::panic::PanicInfo;

use hydrorattle::linalg::{cholesky, cholesky_solve, sym_matvec, tri};
use hydrorattle::mobility::{Hydro, assemble_grand, assemble_tt};
use hydrorattle::{
    BondSet, Layout, Method, NoForce, Params, Particle, ParticleSet, Real, SolverKind, Storage,
    step,
};

const N: usize = 4;
const B: usize = N - 1;
/// Storage for every method at this size, counted at compile time.
const L: Layout = Layout::all(N, B);

/// An empty state in a `static`: everything in the kernel is `const`-constructible.
static EMPTY_F32: ParticleSet<f32, N> = ParticleSet::new();
static EMPTY_F64: ParticleSet<f64, N> = ParticleSet::new();

/// Everything the kernel offers a firmware caller, once. `Err(())` on any failure.
fn exercise<T: Real>(empty: &ParticleSet<T, N>) -> Result<(), ()> {
    // A bent 4-bead chain: head of radius 1.26, tails of radius 1, bonds 1.5 (a_i + a_j).
    let mut ps = empty.clone();
    let radii = [1.26, 1.0, 1.0, 1.0];
    let centres = [
        [0.0, 0.0, 0.0],
        [3.39, 0.0, 0.0],
        [3.39, 3.0, 0.0],
        [3.39, 3.0, 3.0],
    ];
    for (c, a) in centres.iter().zip(radii) {
        let density = black_box(T::from_f64(4.5));
        let p = Particle::new(T::v3_from(*c), T::from_f64(a), density);
        ps.push(p).map_err(|_| ())?;
    }
    ps.validate(false).map_err(|_| ())?;
    let bonds = BondSet::<T, B>::chain(&ps.pos).map_err(|_| ())?;
    let eta = black_box(T::ONE);

    // Translational mobility: assemble, product, factorise, solve.
    let mut tt = [T::M3_ZERO; tri(N)];
    assemble_tt(Hydro::Rpy, eta, &ps.pos, &ps.radius, &mut tt).map_err(|_| ())?;
    let force = [T::v3(T::ZERO, T::ZERO, -T::ONE); N];
    let mut u = [T::V3_ZERO; N];
    sym_matvec::<T>(&tt, N, &force, &mut u);
    cholesky::<T>(&mut tt, N).map_err(|_| ())?;
    cholesky_solve::<T>(&tt, N, &mut u); // back to the forces
    black_box(&u);

    // Grand mobility (translations and rotations).
    let mut grand = [T::M3_ZERO; tri(2 * N)];
    assemble_grand(Hydro::Rpy, eta, &ps.pos, &ps.radius, &mut grand).map_err(|_| ())?;
    cholesky::<T>(&mut grand, 2 * N).map_err(|_| ())?;
    let mut w = [T::v3(T::ONE, T::ZERO, T::ZERO); 2 * N];
    cholesky_solve::<T>(&grand, 2 * N, &mut w);
    black_box(&w);

    // Full steps of every method, with storage on the stack sized by a const layout.
    let mut store = Storage::<T, { L.blocks }, { L.vectors }, { L.scalars }, { L.indices }>::new();
    let mut ws = store.workspace();
    let methods = [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
        Method::Springs,
    ];
    for method in methods {
        for rotation in [false, true] {
            let mut p = Params::new(black_box(T::from_f64(0.01)));
            p.method = method;
            p.rotation = rotation;
            p.solver.kind = if rotation {
                SolverKind::Sweep
            } else {
                SolverKind::Newton
            };
            let mut state = ps.clone();
            let report = step(&mut state, &bonds, &p, &mut ws, &mut NoForce).map_err(|_| ())?;
            black_box((&state.pos, &state.vel, &state.omega, report.residual));
        }
    }
    Ok(())
}

/// Runs the kernel in both precisions; the exit status says whether all went well.
extern "C" fn canary_main() -> ! {
    let ok = exercise::<f32>(&EMPTY_F32).is_ok() && exercise::<f64>(&EMPTY_F64).is_ok();
    exit(if ok { 0 } else { 1 })
}

#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    exit(101)
}

// --- Host (x86_64 Linux): our own `_start` and `exit`, no C runtime. ---

/// Process entry: the kernel enters with `rsp` 16-byte aligned and no return address,
/// so align explicitly and call into Rust.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[unsafe(naked)]
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    core::arch::naked_asm!(
        "xor ebp, ebp",
        "and rsp, -16",
        "call {main}",
        "ud2",
        main = sym canary_main,
    )
}

#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
fn exit(code: i32) -> ! {
    // SAFETY: the `exit_group` system call takes one integer and never returns.
    unsafe {
        core::arch::asm!(
            "syscall",
            in("rax") 231,
            in("rdi") code,
            options(noreturn, nostack)
        )
    }
}

// --- Bare metal (thumbv7em-none-eabihf and others): reset entry, park afterwards. ---

#[cfg(not(all(target_arch = "x86_64", target_os = "linux")))]
#[unsafe(no_mangle)]
pub extern "C" fn _start() -> ! {
    canary_main()
}

#[cfg(not(all(target_arch = "x86_64", target_os = "linux")))]
fn exit(code: i32) -> ! {
    black_box(code);
    loop {
        core::hint::spin_loop();
    }
}
