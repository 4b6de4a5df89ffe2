//! The product's work in a fixed number of pieces for the storage's [`Parallel`]: the
//! pieces depend on the sizes alone and each value's arithmetic is the same in whichever
//! piece it falls, so any number of threads gives the bits of one.

use crate::parallel::{BANDS, Jobs, Parallel, run_all};

/// Pieces per parallel phase.
pub(super) const JOBS: usize = BANDS;

/// The item range `[a, b)` of piece `t` of `total` items.
#[inline]
pub(super) fn range(total: usize, t: usize) -> [usize; 2] {
    [total * t / JOBS, total * (t + 1) / JOBS]
}

/// A slice cut into pieces: piece `[a, b)` takes `len(a, b)` elements.
pub(super) type Cut<'s, X> = (&'s mut [X], &'s (dyn Fn(usize, usize) -> usize + Sync));

/// `(b - a) unit` elements: rows of the piece's items.
pub(super) fn rows(unit: usize) -> impl Fn(usize, usize) -> usize + Sync {
    move |a, b| (b - a) * unit
}

/// `a unit` elements: a row for each item of the pieces before.
pub(super) fn before(unit: usize) -> impl Fn(usize, usize) -> usize + Sync {
    move |a, _| a * unit
}

/// `each` elements, whatever the piece: its own scratch.
pub(super) fn fixed(each: usize) -> impl Fn(usize, usize) -> usize + Sync {
    move |_, _| each
}

/// Cuts `total` items into [`JOBS`] pieces and the three slices by their rules, runs
/// `job([a, b], x, y, z)` for each through `par`, and returns the first error in piece
/// order (the one a single pass in item order meets first).
pub(super) fn pieces<X: Send, Y: Send, Z: Send, E: Send, J>(
    par: &dyn Parallel,
    total: usize,
    (x, y, z): (Cut<'_, X>, Cut<'_, Y>, Cut<'_, Z>),
    job: J,
) -> Result<(), E>
where
    J: Fn([usize; 2], &mut [X], &mut [Y], &mut [Z]) -> Result<(), E> + Sync,
{
    let mut results: [Option<Result<(), E>>; JOBS] = core::array::from_fn(|_| None);
    {
        let mut jobs = Jobs::new();
        let ((mut xs, lx), (mut ys, ly), (mut zs, lz)) = (x, y, z);
        let job = &job;
        for (t, result) in results.iter_mut().enumerate() {
            let [a, b] = range(total, t);
            let (xp, rest) = core::mem::take(&mut xs).split_at_mut(lx(a, b));
            xs = rest;
            let (yp, rest) = core::mem::take(&mut ys).split_at_mut(ly(a, b));
            ys = rest;
            let (zp, rest) = core::mem::take(&mut zs).split_at_mut(lz(a, b));
            zs = rest;
            let _ = jobs.push(move || *result = Some(job([a, b], xp, yp, zp)));
        }
        run_all(par, &mut jobs);
    }
    for r in results {
        r.unwrap_or(Ok(()))?;
    }
    Ok(())
}

/// No slice.
pub(super) fn none<'s>() -> Cut<'s, ()> {
    (&mut [], &|_, _| 0)
}
