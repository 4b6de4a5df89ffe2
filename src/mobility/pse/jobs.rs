//! PSE's work in a fixed number of pieces for the workspace's [`Parallel`]: the
//! pieces depend on the sizes alone, and each element's arithmetic is the same in
//! whichever piece it falls, so any number of threads gives the bits of one.

use crate::parallel::{BANDS, Jobs, Parallel, run_all};

/// Pieces per parallel phase.
pub(super) const JOBS: usize = BANDS;

/// No scratch for [`pieces`].
#[inline(always)]
pub(super) fn none<'a>() -> (&'a mut [()], usize) {
    (&mut [], 0)
}

/// Splits `data` into [`JOBS`] pieces of `(b - a) * unit` elements, item ranges
/// `a = total t / JOBS .. b = total (t + 1) / JOBS`, and `aux` into pieces of `each`
/// (a job's own scratch; `each = 0` for none), runs `job(a, piece, aux_piece)` for
/// each through `par`, and returns the first error in piece order (the one a single
/// pass in item order meets first).
pub(super) fn pieces<X: Send, Y: Send, E: Send, J>(
    par: &dyn Parallel,
    (data, total, unit): (&mut [X], usize, usize),
    (aux, each): (&mut [Y], usize),
    job: J,
) -> Result<(), E>
where
    J: Fn(usize, &mut [X], &mut [Y]) -> Result<(), E> + Sync,
{
    let mut results: [Option<Result<(), E>>; JOBS] = core::array::from_fn(|_| None);
    {
        let mut jobs = Jobs::new();
        let (mut rest, mut aux_rest) = (data, aux);
        let job = &job;
        for (t, result) in results.iter_mut().enumerate() {
            let (a, b) = (total * t / JOBS, total * (t + 1) / JOBS);
            let (piece, tail) = core::mem::take(&mut rest).split_at_mut((b - a) * unit);
            rest = tail;
            let (own, tail) = core::mem::take(&mut aux_rest).split_at_mut(each);
            aux_rest = tail;
            let _ = jobs.push(move || *result = Some(job(a, piece, own)));
        }
        run_all(par, &mut jobs);
    }
    for r in results {
        r.unwrap_or(Ok(()))?;
    }
    Ok(())
}
