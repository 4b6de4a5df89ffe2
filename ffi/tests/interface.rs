//! The C interface from Rust: a good step gives the kernel's bits, and every kind of
//! bad input returns its error code (never undefined behaviour, never a panic).

use core::ffi::c_void;
use core::ptr::{null, null_mut};

use hydrorattle_ffi::*;

/// The Figure 1 (c) chain and its bonds, through the interface's own helper.
struct Chain {
    pos: [[f32; 3]; 25],
    vel: [[f32; 3]; 25],
    omega: [[f32; 3]; 25],
    radius: [f32; 25],
    density: [f32; 25],
    bonds: [HrBondF32; 24],
}

fn chain() -> Chain {
    let mut c = Chain {
        pos: [[0.0; 3]; 25],
        vel: [[0.0; 3]; 25],
        omega: [[0.0; 3]; 25],
        radius: [0.0; 25],
        density: [0.0; 25],
        bonds: [HrBond {
            i: 0,
            j: 0,
            length: 0.0,
        }; 24],
    };
    let s = unsafe {
        hr_figure1c_f32(
            c.pos.as_mut_ptr(),
            c.radius.as_mut_ptr(),
            c.density.as_mut_ptr(),
            c.bonds.as_mut_ptr(),
        )
    };
    assert_eq!(s, HrStatus::Ok);
    c
}

fn state(c: &mut Chain) -> HrStateF32 {
    HrState {
        n: 25,
        pos: c.pos.as_mut_ptr(),
        vel: c.vel.as_mut_ptr(),
        omega: c.omega.as_mut_ptr(),
        radius: c.radius.as_ptr(),
        density: c.density.as_ptr(),
        time: 0.0,
        noise: null_mut(),
    }
}

fn scene_params(method: HrMethod) -> HrParamsF32 {
    let mut p = hr_params_default_f32(0.005);
    p.method = method as u32;
    p.solver = HrSolver::Newton as u32;
    p.max_iterations = 500;
    p.allow_overlap = 1;
    p
}

/// The scene's soft contact as a C callback (stiffness in `user`).
unsafe extern "C" fn contact(
    user: *mut c_void,
    n: usize,
    pos: *const [f32; 3],
    radius: *const f32,
    force: *mut [f32; 3],
) {
    let k = unsafe { *(user as *const f32) };
    let (pos, radius) = unsafe {
        (
            core::slice::from_raw_parts(pos, n),
            core::slice::from_raw_parts(radius, n),
        )
    };
    let force = unsafe { core::slice::from_raw_parts_mut(force, n) };
    for i in 0..n {
        for j in 0..i {
            let r = [
                pos[i][0] - pos[j][0],
                pos[i][1] - pos[j][1],
                pos[i][2] - pos[j][2],
            ];
            let reach = radius[i] + radius[j];
            let s2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            if s2 < reach * reach && s2 > 0.0 {
                let s = s2.sqrt();
                let c = k * (reach - s) / s;
                for d in 0..3 {
                    force[i][d] += r[d] * c;
                    force[j][d] -= r[d] * c;
                }
            }
        }
    }
}

fn run(c: &mut Chain, p: &HrParamsF32, steps: u32) -> (HrStatus, HrReportF32, HrStateF32) {
    let bytes = unsafe { hr_storage_bytes_f32(p, 25, 24) };
    assert!(bytes > 0);
    let mut storage = vec![0u8; bytes];
    let mut k = 1000.0f32;
    let mut st = state(c);
    let mut report = HrReport::default();
    for _ in 0..steps {
        let s = unsafe {
            hr_step_f32(
                &mut st,
                c.bonds.as_ptr(),
                24,
                p,
                storage.as_mut_ptr().cast(),
                bytes,
                Some(contact),
                (&mut k as *mut f32).cast(),
                &mut report,
            )
        };
        if s != HrStatus::Ok {
            return (s, report, st);
        }
    }
    (HrStatus::Ok, report, st)
}

#[test]
fn steps_give_the_firmware_scene_bits() {
    // The C callback here is the kernel's SoftContact written out, so the run must
    // match the scene's host run bit for bit (digest and report).
    let host = scene::host_summaries(&["overdamped"]);
    let mut c = chain();
    let (s, report, st) = run(&mut c, &scene_params(HrMethod::Overdamped), scene::STEPS);
    assert_eq!(s, HrStatus::Ok);
    let digest = scene::digest_triples(&c.pos);
    assert!(host.contains(&format!("digest={digest:016x}")), "{host}");
    assert!(host.contains(&format!("iterations={} ", report.iterations)));
    assert!((st.time - 1.0).abs() < 1e-3);
}

#[test]
fn every_method_steps_in_both_precisions() {
    for m in [
        HrMethod::Overdamped,
        HrMethod::Overdamped2,
        HrMethod::Rattle,
        HrMethod::RattleStable,
        HrMethod::Springs,
    ] {
        let mut c = chain();
        assert_eq!(run(&mut c, &scene_params(m), 3).0, HrStatus::Ok, "{m:?}");
    }
    // f64: a dimer with no callback.
    let mut pos = [[0.0f64, 0.0, 0.0], [3.0, 0.0, 0.0]];
    let (mut vel, mut omega) = ([[0.0f64; 3]; 2], [[0.0f64; 3]; 2]);
    let (radius, density) = ([1.0f64; 2], [4.5f64; 2]);
    let bonds = [HrBond {
        i: 0,
        j: 1,
        length: 3.0f64,
    }];
    let p = hr_params_default_f64(0.01);
    let bytes = unsafe { hr_storage_bytes_f64(&p, 2, 1) };
    let mut storage = vec![0u64; bytes.div_ceil(8)];
    let mut st = HrState {
        n: 2,
        pos: pos.as_mut_ptr(),
        vel: vel.as_mut_ptr(),
        omega: omega.as_mut_ptr(),
        radius: radius.as_ptr(),
        density: density.as_ptr(),
        time: 0.0,
        noise: null_mut(),
    };
    let s = unsafe {
        hr_step_f64(
            &mut st,
            bonds.as_ptr(),
            1,
            &p,
            storage.as_mut_ptr().cast(),
            bytes,
            None,
            null_mut(),
            null_mut(),
        )
    };
    assert_eq!(s, HrStatus::Ok);
    assert!(pos[0][2] < 0.0 && st.time == 0.01);
}

/// One step of the chain with `edit` applied to the arguments first.
fn step_with(
    edit: impl FnOnce(&mut HrStateF32, &mut HrParamsF32, &mut Args),
) -> (HrStatus, HrReportF32) {
    let mut c = chain();
    let mut p = scene_params(HrMethod::Overdamped);
    let bytes = unsafe { hr_storage_bytes_f32(&p, 25, 24) };
    let mut storage = vec![0u32; bytes.div_ceil(4) + 1];
    let mut st = state(&mut c);
    let mut a = Args {
        bonds: c.bonds.as_ptr(),
        n_bonds: 24,
        storage: storage.as_mut_ptr().cast(),
        bytes,
    };
    edit(&mut st, &mut p, &mut a);
    let before = c.pos;
    let mut report = HrReport::default();
    let s = unsafe {
        hr_step_f32(
            &mut st,
            a.bonds,
            a.n_bonds,
            &p,
            a.storage,
            a.bytes,
            None,
            null_mut(),
            &mut report,
        )
    };
    if s != HrStatus::Ok {
        assert_eq!(
            before.map(|v| v.map(f32::to_bits)),
            c.pos.map(|v| v.map(f32::to_bits)),
            "state touched"
        );
    }
    (s, report)
}

struct Args {
    bonds: *const HrBondF32,
    n_bonds: usize,
    storage: *mut c_void,
    bytes: usize,
}

#[test]
fn null_pointers_are_refused() {
    assert_eq!(
        step_with(|s, _, _| s.pos = null_mut()).0,
        HrStatus::NullPointer
    );
    assert_eq!(
        step_with(|s, _, _| s.radius = null()).0,
        HrStatus::NullPointer
    );
    assert_eq!(
        step_with(|_, _, a| a.storage = null_mut()).0,
        HrStatus::NullPointer
    );
    assert_eq!(
        step_with(|_, _, a| a.bonds = null()).0,
        HrStatus::NullPointer
    );
    let p = hr_params_default_f32(0.01);
    let s = unsafe {
        hr_step_f32(
            null_mut(),
            null(),
            0,
            &p,
            null_mut(),
            0,
            None,
            null_mut(),
            null_mut(),
        )
    };
    assert_eq!(s, HrStatus::NullPointer);
    assert_eq!(unsafe { hr_storage_bytes_f32(null(), 25, 24) }, 0);
    let s = unsafe { hr_figure1c_f32(null_mut(), null_mut(), null_mut(), null_mut()) };
    assert_eq!(s, HrStatus::NullPointer);
}

#[test]
fn storage_too_small_is_refused_with_the_need() {
    let (s, r) = step_with(|_, _, a| a.bytes -= 1);
    assert_eq!(s, HrStatus::Storage);
    assert_eq!(r.error_index, r.error_other + 1);
}

#[test]
fn sizes_out_of_range_are_refused() {
    let p = hr_params_default_f32(0.01);
    assert_eq!(
        unsafe { hr_storage_bytes_f32(&p, hr_max_particles() + 1, 0) },
        0
    );
    assert_eq!(
        unsafe { hr_storage_bytes_f32(&p, 2, hr_max_bonds() + 1) },
        0
    );
    assert_eq!(
        unsafe { hr_storage_bytes_f32(&p, usize::MAX, usize::MAX) },
        0
    );
    assert_eq!(step_with(|s, _, _| s.n = usize::MAX).0, HrStatus::Size);
    assert_eq!(
        step_with(|_, _, a| a.n_bonds = usize::MAX).0,
        HrStatus::Size
    );
    // More bonds than the array holds is the caller's lie; an index out of range is not.
    let (s, r) = step_with(|s, _, _| s.n = 24);
    assert_eq!((s, r.error_index), (HrStatus::Bond, 23));
}

#[test]
fn nan_and_bad_values_come_back_as_kernel_errors() {
    assert_eq!(
        step_with(|_, p, _| p.dt = f32::NAN).0,
        HrStatus::BadTimeStep
    );
    assert_eq!(
        step_with(|_, p, _| p.viscosity = f32::NAN).0,
        HrStatus::BadParameter
    );
    assert_eq!(
        step_with(|_, p, _| p.gravity[1] = f32::INFINITY).0,
        HrStatus::BadParameter
    );
    assert_eq!(
        step_with(|_, p, _| p.tolerance = f32::NAN).0,
        HrStatus::BadParameter
    );
    assert_eq!(
        step_with(|_, p, _| p.max_iterations = 0).0,
        HrStatus::BadParameter
    );
    let (s, r) = step_with(|s, _, _| unsafe { (*s.pos.add(7))[1] = f32::NAN });
    assert_eq!((s, r.error_index), (HrStatus::Particle, 7));
}

#[test]
fn unknown_enum_values_are_refused() {
    assert_eq!(step_with(|_, p, _| p.method = 5).0, HrStatus::Enum);
    assert_eq!(step_with(|_, p, _| p.solver = u32::MAX).0, HrStatus::Enum);
    assert_eq!(step_with(|_, p, _| p.hydro = 3).0, HrStatus::Enum);
    let mut p = hr_params_default_f32(0.01);
    p.method = 9;
    assert_eq!(unsafe { hr_storage_bytes_f32(&p, 25, 24) }, 0);
}

#[test]
fn misaligned_and_overlapping_arrays_are_refused() {
    let (s, _) = step_with(|s, _, _| s.vel = unsafe { s.vel.byte_add(1) });
    assert_eq!(s, HrStatus::Alignment);
    assert_eq!(step_with(|s, _, _| s.vel = s.pos).0, HrStatus::Aliasing);
    assert_eq!(
        step_with(|s, _, _| s.density = s.omega.cast()).0,
        HrStatus::Aliasing
    );
    assert_eq!(
        step_with(|s, _, a| a.storage = s.pos.cast()).0,
        HrStatus::Aliasing
    );
    // Read-only arrays may share memory.
    assert_eq!(step_with(|s, _, _| s.density = s.radius).0, HrStatus::Ok);
    // Storage at an odd address is realigned inside the buffer (one spare word).
    assert_eq!(
        step_with(|_, _, a| a.storage = unsafe { a.storage.byte_add(1) }).0,
        HrStatus::Ok
    );
}

#[test]
fn every_status_has_a_message() {
    for code in -6..=13 {
        let m = unsafe { core::ffi::CStr::from_ptr(hr_error_message(code)) };
        assert!(!m.to_bytes().is_empty());
    }
}

/// `HrParams::near_field` reaches the kernel's `Params::near`: off by default with the
/// kernel's defaults beside it, its storage counted only when on, the chain steps with
/// it (and moves otherwise than without), and a method it does not serve is refused.
#[test]
fn the_near_field_is_a_choice_of_the_parameters() {
    let off = scene_params(HrMethod::Overdamped2);
    assert_eq!(off.near_field, 0);
    assert_eq!(
        (off.near_cutoff, off.near_wall_cutoff, off.near_min_gap),
        (4.0, 4.0, 1e-3)
    );
    let mut on = off;
    on.near_field = 1;
    let bytes = |p: &HrParamsF32| unsafe { hr_storage_bytes_f32(p, 25, 24) };
    assert!(bytes(&on) > bytes(&off));
    let (mut c1, mut c2) = (chain(), chain());
    let (s, _, far) = run(&mut c1, &off, 2);
    assert_eq!(s, HrStatus::Ok);
    let (s, _, near) = run(&mut c2, &on, 2);
    assert_eq!(s, HrStatus::Ok);
    let moved = |st: &HrStateF32| unsafe { *st.pos };
    assert_ne!(moved(&far), moved(&near));
    let mut rattle = scene_params(HrMethod::Rattle);
    rattle.near_field = 1;
    let (s, _, _) = run(&mut chain(), &rattle, 1);
    assert_eq!(s, HrStatus::Unsupported);
}
