//! Stokesian dynamics' near field in a step ([`Params::near`]): the step's stored
//! mobility is the translational part of the dense Stokesian dynamics grand mobility
//! ([`crate::stokesian::mobility`]), and the spins read its rotation-translation part.
//!
//! Why the translational blocks alone: the spheres are torque-free, so the force-torque
//! balance `(U, W) = M_SD (F, 0)` gives `U = M_SD,tt F` and `W = M_SD,rt F`. With
//! `M_SD,tt` stored where the far field's `mu_tt` would be (nine-scalar blocks: the
//! near field's many-body blocks need not be symmetric), every stage that reads the
//! stored mobility reads it unchanged: the unconstrained move, the constraint solvers'
//! metric (sweep, Newton, Krylov), the contacts' and the wall's projection, and the
//! thermal noise's Cholesky factor and midpoint. The dense `6n x 6n` matrix and the
//! far field's packed blocks it is formed from are the step's storage
//! ([`Views::near`](crate::workspace::Views), sized by
//! [`Layout::for_params`](crate::Layout::for_params) only with the near field on).
//!
//! Without the kernel's `near` feature [`Params::near_on`] is `false` as a constant, so
//! every call here folds away; the functions then refuse, never reached.

use core::cell::Cell;

use crate::error::StepError;
use crate::linalg::{MobMut, tri, with_blocks};
use crate::params::{Method, Params};
use crate::real::Real;
#[cfg(feature = "near")]
use crate::stokesian::Far;

use super::stages::Sums;

/// The near field's storage: the far field's packed grand mobility, the dense
/// Stokesian dynamics mobility ([`crate::stokesian::storage`]) followed, in a Brownian
/// step with rotation, by the start's rotation-translation blocks kept for the spins
/// ([`keep_spin`]), and the count of `M_SD` formed in the step
/// ([`StepReport::near_formations`](super::StepReport::near_formations)).
pub(super) type Store<'a, T> = (&'a mut [<T as Real>::M3], &'a mut [T], &'a Cell<u32>);

/// Where [`spin`] reads `M_SD,rt` at the start of the step.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Spins {
    /// The store's dense matrix holds `M_SD` at the start.
    Dense,
    /// The copy [`keep_spin`] made (the midpoint's mobility has since taken the dense
    /// matrix); formed again if the storage has no room for it.
    Kept,
}

/// Refuses the combinations the near field does not serve (a typed
/// [`StepError::Unsupported`] naming each), and parameters out of range.
pub(super) fn check<T: Real>(p: &Params<T>, n: usize, thermal: bool) -> Result<(), StepError> {
    if !p.near_on() {
        return Ok(());
    }
    #[cfg(feature = "near")]
    if let Some(nf) = p.near {
        let ok = |v: T| v.is_finite() && v >= T::ZERO;
        if !(ok(nf.cutoff) && ok(nf.wall_cutoff) && ok(nf.min_gap) && nf.min_gap > T::ZERO) {
            return Err(StepError::BadParameter(
                "near (cutoff and wall_cutoff finite and >= 0, min_gap finite and > 0)",
            ));
        }
    }
    let refuse = |what| Err(StepError::Unsupported(what));
    if p.hydro != crate::mobility::Hydro::Rpy {
        return refuse("the near field with a far field other than RPY");
    }
    if !matches!(p.method, Method::Overdamped | Method::Overdamped2) {
        return refuse("the near field with a method other than Overdamped or Overdamped2");
    }
    // The iterative near field (`near_iter.rs`) reads no block of `M_SD`: its far field
    // is the assembled grand mobility, or with `Params::pse` the fast product's grand
    // product (free space's, or PSE's in a box: `near_iter/solve.rs`). PSE's own
    // refusals (rotation, the solvers that read blocks) are the box's checks'.
    if p.matrix_free {
        return Ok(());
    }
    if p.place().cell().is_some() && p.pse.is_some() {
        return refuse(
            "the near field with the PSE sums in a box (its dense mobility reads the Ewald sums' blocks: pse = None)",
        );
    }
    if thermal && p.lanczos_noise(n) {
        return refuse(
            "the near field with Lanczos noise (noise_sqrt = Cholesky, or Auto up to LANCZOS_CROSSOVER beads)",
        );
    }
    Ok(())
}

/// The Stokesian dynamics grand mobility at `pos` into the store's dense matrix, and its
/// translational blocks into `mu` (packed lower triangle, nine scalars a block).
pub(super) fn assemble_tt<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    mu: MobMut<'_, T>,
    store: &mut Store<'_, T>,
) -> Result<(), StepError> {
    let n = pos.len();
    dense(p, ew, pos, radius, store)?;
    let (m, d) = (6 * n, &*store.1);
    let mu = mu.general();
    if mu.len() < tri(n) {
        return Err(StepError::Unsupported(
            "the near field with symmetric stored blocks",
        ));
    }
    for i in 0..n {
        for j in 0..=i {
            let col = |c: usize| {
                let at = |r: usize| d[(3 * i + r) * m + 3 * j + c];
                T::v3(at(0), at(1), at(2))
            };
            mu[tri(i) + j] = T::m3_cols(col(0), col(1), col(2));
        }
    }
    Ok(())
}

/// `u = M_SD,tt(pos) f`: assembled into `mu` ([`assemble_tt`]) and applied.
#[allow(clippy::too_many_arguments)]
pub(super) fn assemble_apply<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    mut mu: MobMut<'_, T>,
    f: &[T::V3],
    u: &mut [T::V3],
    store: &mut Store<'_, T>,
) -> Result<(), StepError> {
    assemble_tt(p, ew, pos, radius, mu.reborrow(), store)?;
    let n = pos.len();
    with_blocks!(mu.as_ref(), a => crate::linalg::sym_matvec::<T>(a, n, f, u));
    Ok(())
}

/// Angular velocities of torque-free spheres, `W = Omega_inf + M_SD,rt F` (`f` the force
/// each sphere exerts on the fluid), with [`Params::rotation`]; `Omega_inf` alone
/// otherwise. `M_SD,rt` at `pos` is read where `from` says ([`Spins`]).
pub(super) fn spin<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    f: &[T::V3],
    out: &mut [T::V3],
    (store, from): (&mut Store<'_, T>, Spins),
) -> Result<(), StepError> {
    out.fill(p.vorticity);
    if !p.rotation {
        return Ok(());
    }
    let n = pos.len();
    let (m, kept) = (6 * n, 9 * n * n);
    let read_kept = from == Spins::Kept && store.1.len() >= m * m + kept;
    if from == Spins::Kept && !read_kept {
        dense(p, ew, pos, radius, store)?;
    }
    let d = &*store.1;
    // Row `k` of sphere `i`'s spin: the dense matrix's row `3 (n + i) + k`, columns
    // `0..3n`, or the same scalars in the kept copy (the same sums, the same bits).
    let row = |i: usize, k: usize| match read_kept {
        true => &d[m * m + (3 * i + k) * 3 * n..][..3 * n],
        false => &d[(3 * (n + i) + k) * m..][..3 * n],
    };
    for (i, w) in out.iter_mut().enumerate() {
        let mut acc = [T::ZERO; 3];
        for (k, a) in acc.iter_mut().enumerate() {
            let row = row(i, k);
            for (j, &fj) in f.iter().enumerate() {
                let [x, y, z] = T::xyz(fj);
                *a += row[3 * j] * x + row[3 * j + 1] * y + row[3 * j + 2] * z;
            }
        }
        *w += T::v3(acc[0], acc[1], acc[2]);
    }
    Ok(())
}

/// Copies `M_SD,rt` (rows `3n..6n`, columns `0..3n`) from the store's dense matrix,
/// which must hold `M_SD` at the start, to the room after it, where the storage has it
/// ([`crate::Layout::for_params`] counts it in a Brownian step with rotation): the
/// midpoint's mobility then takes the dense matrix, and the spins read the copy instead
/// of forming `M_SD` at the start a second time (two dense inversions of `6n x 6n`).
pub(super) fn keep_spin<T: Real>(n: usize, store: &mut Store<'_, T>) {
    let m = 6 * n;
    let Some((d, kept)) = store.1.split_at_mut_checked(m * m) else {
        return;
    };
    let Some(kept) = kept.get_mut(..9 * n * n) else {
        return;
    };
    for (r, row) in kept.chunks_exact_mut(3 * n).enumerate() {
        row.copy_from_slice(&d[(3 * n + r) * m..][..3 * n]);
    }
}

/// The far field the step's near field corrects: the step's geometry with its sums
/// (`ew`: the box's Ewald sums).
#[cfg(feature = "near")]
pub(super) fn far<'a, T: Real>(p: &Params<T>, ew: Sums<'a, T>) -> Result<Far<'a, T>, StepError> {
    // A box summed by PSE (the iterative near field's) is a far field without blocks.
    Far::at(p.place(), ew).ok_or(StepError::Unsupported(
        "the near field in a box without the Ewald sums",
    ))
}

/// `M_SD(pos)` into the store's dense matrix (free space, above the step's wall, or in
/// the step's periodic box with its Ewald sums `ew`).
#[cfg(feature = "near")]
fn dense<T: Real>(
    p: &Params<T>,
    ew: Sums<'_, T>,
    pos: &[T::V3],
    radius: &[T],
    store: &mut Store<'_, T>,
) -> Result<(), StepError> {
    use crate::stokesian::mobility_in;
    let Some(nf) = p.near else {
        return Err(StepError::Unsupported(
            "the near field's mobility without Params::near",
        ));
    };
    let far = far(p, ew)?;
    store.2.set(store.2.get() + 1);
    let (packed, out) = (&mut *store.0, &mut *store.1);
    mobility_in(p.viscosity, far, pos, radius, nf, packed, out).map_err(sd_error)
}

/// The step's error for the Stokesian dynamics mobility's.
#[cfg(feature = "near")]
pub(super) fn sd_error(e: crate::stokesian::SdError) -> StepError {
    use crate::stokesian::SdError;
    match e {
        SdError::Particle(e) => StepError::Particle(e),
        SdError::NotPositiveDefinite(error) => StepError::Linalg {
            stage: crate::error::Stage::Mobility,
            error,
        },
        SdError::Near { .. } => StepError::Unsupported(
            "the near field of a pair whose size ratio is outside 0.1 to 10 (or a sphere's radius not positive)",
        ),
        SdError::Params => StepError::BadParameter("near"),
        SdError::Storage => StepError::Unsupported("the near field without its storage"),
        SdError::Far(e) => e,
        SdError::NotConverged {
            iterations,
            residual,
        } => StepError::NoConvergence {
            stage: crate::error::Stage::Mobility,
            iterations,
            residual,
        },
    }
}

/// Without the `near` feature there is no near field to form (never reached:
/// [`Params::near_on`] is `false`).
#[cfg(not(feature = "near"))]
fn dense<T: Real>(
    _: &Params<T>,
    _: Sums<'_, T>,
    _: &[T::V3],
    _: &[T],
    _: &mut Store<'_, T>,
) -> Result<(), StepError> {
    Err(StepError::Unsupported(
        "the near field: the kernel was built without its `near` feature",
    ))
}
