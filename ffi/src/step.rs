//! The generic body behind `hr_step_f32`/`hr_step_f64`: every pointer and count the C
//! caller passed is checked (null, alignment, range, overlap) before any Rust
//! reference to the caller's memory is formed; then the storage buffer is carved into
//! the kernel's workspace and one step runs.

use core::ffi::c_void;
use core::mem::{align_of, size_of};

use kernel::{Bond, ExternalForce, Layout, Noise, Params, Real, State, StepError, Workspace};

use crate::types::{HrBond, HrNoise, HrParams, HrReport, HrState, HrStatus};

/// Most particles a call accepts: keeps every storage count within `usize` on 32-bit
/// targets (the kernel's layout is `O(n^2)` blocks).
pub(crate) const MAX_PARTICLES: usize = if usize::BITS >= 64 { 1 << 20 } else { 4096 };
/// Most bonds a call accepts (the dense solvers' storage is `O(bonds^2)`).
pub(crate) const MAX_BONDS: usize = 2 * MAX_PARTICLES;

/// The C force callback: adds forces into `force` (`n` triples, already holding the
/// buoyant weight) for candidate positions `pos`.
pub type HrForce<T> = Option<
    unsafe extern "C" fn(
        user: *mut c_void,
        n: usize,
        pos: *const [T; 3],
        radius: *const T,
        force: *mut [T; 3],
    ),
>;
/// `f32` force callback.
pub type HrForceF32 = HrForce<f32>;
/// `f64` force callback.
pub type HrForceF64 = HrForce<f64>;

/// A precision the interface offers: the kernel's vectors must be `[T; 3]` in memory.
pub trait Precision: Real {
    /// Alignment every storage array is placed at.
    const ALIGN: usize;
}

macro_rules! precision {
    ($t:ty) => {
        const _: () = assert!(
            size_of::<<$t as Real>::V3>() == size_of::<[$t; 3]>()
                && align_of::<<$t as Real>::V3>() == align_of::<$t>()
                && size_of::<<$t as Real>::M3>() == 9 * size_of::<$t>()
                && align_of::<<$t as Real>::M3>() == align_of::<$t>()
        );
        impl Precision for $t {
            const ALIGN: usize = max(max(align_of::<$t>(), align_of::<usize>()), 8);
        }
    };
}

const fn max(a: usize, b: usize) -> usize {
    if a > b { a } else { b }
}

precision!(f32);
precision!(f64);

/// Bytes of one array of `count` elements of `X`, rounded up to the storage alignment.
fn array_bytes<T: Precision, X>(count: usize) -> Option<usize> {
    let raw = count.checked_mul(size_of::<X>())?;
    raw.checked_next_multiple_of(T::ALIGN)
}

/// Storage bytes for a step with `p`: the kernel's layout, a copy of the bonds, and
/// room to align the buffer's start. `None` when a count is out of range.
pub fn bytes_needed<T: Precision>(p: &Params<T>, n: usize, nb: usize) -> Option<usize> {
    if n > MAX_PARTICLES || nb > MAX_BONDS {
        return None;
    }
    let l = Layout::for_params(p, n, nb);
    let parts = [
        array_bytes::<T, Bond<T>>(nb)?,
        array_bytes::<T, T::M3>(l.blocks)?,
        array_bytes::<T, T::V3>(l.vectors)?,
        array_bytes::<T, T>(l.scalars)?,
        array_bytes::<T, usize>(l.indices)?,
    ];
    parts
        .iter()
        .try_fold(T::ALIGN - 1, |acc, &b| acc.checked_add(b))
}

/// A byte range of caller memory, for the overlap check.
#[derive(Clone, Copy)]
struct Span {
    start: usize,
    end: usize,
    written: bool,
}

fn span<X>(p: *const X, count: usize, written: bool) -> Span {
    let start = p as usize;
    Span {
        start,
        end: start.saturating_add(count.saturating_mul(size_of::<X>())),
        written,
    }
}

/// Null, alignment and overlap checks of the caller's arrays.
fn check_pointers(spans: &[(Span, usize)]) -> Result<(), HrStatus> {
    for &(s, align) in spans {
        if s.start == 0 {
            return Err(HrStatus::NullPointer);
        }
        if s.start % align != 0 {
            return Err(HrStatus::Alignment);
        }
    }
    for (a, &(x, _)) in spans.iter().enumerate() {
        for &(y, _) in &spans[a + 1..] {
            let disjoint = x.end <= y.start || y.end <= x.start || x.start == x.end;
            if (x.written || y.written) && !disjoint && y.start != y.end {
                return Err(HrStatus::Aliasing);
            }
        }
    }
    Ok(())
}

/// Takes `count` elements of `X` off the front of the aligned buffer `[at, end)`.
///
/// # Safety
/// `[at, end)` must be caller storage that nothing else references during the step.
unsafe fn take<'a, T: Precision, X>(at: &mut usize, end: usize, count: usize) -> &'a mut [X] {
    let p = *at as *mut X;
    // The caller sized the buffer with `storage_bytes`, which counts this array.
    *at += array_bytes::<T, X>(count).unwrap_or(0);
    debug_assert!(*at <= end);
    // SAFETY: in bounds and aligned (every array starts at a multiple of `T::ALIGN`);
    // the bytes are initialised (documented requirement) and every bit pattern is a
    // valid float or integer; no other reference to them exists (checked overlaps).
    unsafe { core::slice::from_raw_parts_mut(p, count) }
}

/// The C callback as the kernel's force hook.
struct CForce<T> {
    f: HrForce<T>,
    user: *mut c_void,
}

impl<T: Precision> ExternalForce<T> for CForce<T> {
    fn add(&mut self, pos: &[T::V3], radius: &[T], force: &mut [T::V3]) {
        if let Some(f) = self.f {
            // SAFETY: the callback's contract (header): it reads `n` positions and
            // radii and adds into `n` forces; the layouts are `[T; 3]` (asserted).
            unsafe {
                f(
                    self.user,
                    pos.len(),
                    pos.as_ptr().cast(),
                    radius.as_ptr(),
                    force.as_mut_ptr().cast(),
                )
            }
        }
    }
}

/// Everything `hr_step_*` does after reading its arguments.
///
/// # Safety
/// The pointers must be valid for the documented counts, or null (refused).
#[allow(clippy::too_many_arguments)]
pub unsafe fn step<T: Precision>(
    state: *mut HrState<T>,
    bonds: *const HrBond<T>,
    nb: usize,
    params: *const HrParams<T>,
    storage: *mut c_void,
    storage_bytes: usize,
    force: HrForce<T>,
    user: *mut c_void,
    report: &mut HrReport<T>,
) -> Result<(), HrStatus> {
    if state.is_null() || params.is_null() || storage.is_null() {
        return Err(HrStatus::NullPointer);
    }
    if !(state as usize).is_multiple_of(align_of::<HrState<T>>())
        || !(params as usize).is_multiple_of(align_of::<HrParams<T>>())
    {
        return Err(HrStatus::Alignment);
    }
    // SAFETY: non-null and aligned; read by value, no reference kept.
    let (st, p) = unsafe { (state.read(), params.read()) };
    let n = st.n;
    let p = p.to_kernel()?;
    let need = bytes_needed(&p, n, nb).ok_or(HrStatus::Size)?;
    if storage_bytes < need {
        report.error_index = need as u64;
        report.error_other = storage_bytes as u64;
        return Err(HrStatus::Storage);
    }
    let (t, v3) = (align_of::<T>(), align_of::<T::V3>());
    let bond_span = if nb == 0 {
        (span(core::ptr::dangling::<HrBond<T>>(), 0, false), 1)
    } else {
        (span(bonds, nb, false), align_of::<HrBond<T>>())
    };
    let noise_span = if st.noise.is_null() {
        (span(core::ptr::dangling::<HrNoise>(), 0, false), 1)
    } else {
        (
            span(st.noise as *const HrNoise, 1, true),
            align_of::<HrNoise>(),
        )
    };
    check_pointers(&[
        noise_span,
        (span(st.pos, n, true), v3),
        (span(st.vel, n, true), v3),
        (span(st.omega, n, true), v3),
        (span(st.radius, n, false), t),
        (span(st.density, n, false), t),
        (span(storage as *const u8, storage_bytes, true), 1),
        (span(state as *const HrState<T>, 1, true), 1),
        (span(params, 1, false), 1),
        bond_span,
    ])?;
    let end = storage as usize + storage_bytes;
    let mut at = (storage as usize).next_multiple_of(T::ALIGN);
    let layout = Layout::for_params(&p, n, nb);
    // SAFETY (all below): the storage was checked to hold `need` bytes and to overlap
    // no other argument; the caller's arrays were checked for null, alignment and
    // overlap, and are valid for `n` (or `nb`) elements by the interface's contract.
    let kbonds: &mut [Bond<T>] = unsafe { take::<T, Bond<T>>(&mut at, end, nb) };
    for (k, b) in kbonds.iter_mut().enumerate() {
        // SAFETY: `bonds` holds `nb` entries (checked non-null and aligned when nb > 0).
        let c = unsafe { bonds.add(k).read() };
        *b = Bond {
            i: c.i as usize,
            j: c.j as usize,
            length: c.length,
        };
    }
    let mut ws = unsafe {
        Workspace::new(
            take::<T, T::M3>(&mut at, end, layout.blocks),
            take::<T, T::V3>(&mut at, end, layout.vectors),
            take::<T, T>(&mut at, end, layout.scalars),
            take::<T, usize>(&mut at, end, layout.indices),
        )
    };
    let mut time = st.time;
    let mut generator = if st.noise.is_null() {
        None
    } else {
        // SAFETY: non-null, aligned and apart from every other argument (checked);
        // read by value, written back below only after a successful step.
        let words = unsafe { st.noise.read() }.words;
        Some(Noise::restore(words).ok_or(HrStatus::BadParameter)?)
    };
    let state_k = unsafe {
        State {
            pos: core::slice::from_raw_parts_mut(st.pos.cast(), n),
            vel: core::slice::from_raw_parts_mut(st.vel.cast(), n),
            omega: core::slice::from_raw_parts_mut(st.omega.cast(), n),
            radius: core::slice::from_raw_parts(st.radius, n),
            density: core::slice::from_raw_parts(st.density, n),
            time: &mut time,
            noise: generator.as_mut(),
        }
    };
    let mut hook = CForce { f: force, user };
    match kernel::step_slices(state_k, kbonds, &p, &mut ws, &mut hook) {
        Ok(r) => {
            report.iterations = r.iterations;
            report.velocity_iterations = r.velocity_iterations;
            report.residual = r.residual;
            report.max_tension = r.max_tension;
            // SAFETY: `state` is valid and aligned (checked); only `time` changes.
            unsafe { (*state).time = time };
            if let Some(g) = generator {
                // SAFETY: `st.noise` is non-null and aligned (checked above).
                unsafe { st.noise.write(HrNoise { words: g.save() }) };
            }
            Ok(())
        }
        Err(e) => Err(describe(e, report)),
    }
}

/// The status of a kernel error, with its parts ([`StepError::index`], ...) written
/// into `r`: the first index (or a count: iterations done go to `error_other`, the
/// contact capacity to `error_index`), the second, the stage, the value and the limit.
fn describe<T>(e: StepError, r: &mut HrReport<T>) -> HrStatus {
    // `r` starts zeroed (`hr_step_*`), so a part the error lacks stays 0.
    let wide = |i: Option<usize>| i.map_or(0, |i| i as u64);
    r.error_stage = e.stage().map_or(0, |s| s as u32 + 1);
    r.error_value = e.value().unwrap_or(0.0);
    r.error_limit = e.limit().unwrap_or(0.0);
    (r.error_index, r.error_other) = match e {
        StepError::NoConvergence { .. } => (0, wide(e.count())),
        StepError::ContactsFull { .. } => (wide(e.count()), 0),
        _ => (wide(e.index()), wide(e.other())),
    };
    match e {
        StepError::BadTimeStep => HrStatus::BadTimeStep,
        StepError::BadParameter(_) => HrStatus::BadParameter,
        StepError::Particle(_) => HrStatus::Particle,
        StepError::Bond(_) => HrStatus::Bond,
        StepError::Linalg { .. } => HrStatus::Linalg,
        StepError::NoConvergence { .. } => HrStatus::NoConvergence,
        StepError::Degenerate { .. } => HrStatus::Degenerate,
        StepError::NonFinite { .. } | StepError::NonFiniteForce { .. } => HrStatus::NonFinite,
        StepError::Overlap { .. } => HrStatus::Overlap,
        StepError::Storage { .. } => HrStatus::Storage,
        StepError::StateLength => HrStatus::StateLength,
        StepError::Unstable { .. } => HrStatus::Unstable,
        StepError::ContactsFull { .. } => HrStatus::ContactsFull,
        StepError::Infeasible { .. } => HrStatus::Infeasible,
        StepError::Unsupported(_) => HrStatus::Unsupported,
    }
}
