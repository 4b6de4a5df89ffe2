//! The bands' jobs: one round runs a job per band through the workspace's [`Parallel`]
//! ([`by_bands`], [`by_bands_and`]), a second adds the bands' partial sums in band
//! order ([`reduce`]). The jobs share no mutable state, so any schedule gives the same
//! bits.

use super::{BANDS, Parallel, band_start, bands};
use crate::real::Real;

/// The job list of one round (at most [`BANDS`] jobs, on the stack).
pub(crate) type Jobs<F> = heapless::Vec<F, BANDS>;

/// Runs one round of jobs through `par`.
pub(crate) fn run_all<F: FnMut() + Send>(par: &dyn Parallel, jobs: &mut Jobs<F>) {
    let mut refs: heapless::Vec<&mut (dyn FnMut() + Send), BANDS> = heapless::Vec::new();
    for job in jobs.iter_mut() {
        let _ = refs.push(job);
    }
    par.run(&mut refs);
}

/// Runs `job(k0, chunk)` through `par` over `items` cut into chunks of whole rows of
/// `per` items (`count` rows; [`BANDS`] chunks of about equal rows, one below
/// `min_rows` rows), `k0` the chunk's first row: for work whose rows are independent
/// of each other, so that any cut gives the same result.
pub(crate) fn by_rows<X: Send, J>(
    par: &dyn Parallel,
    count: usize,
    per: usize,
    min_rows: usize,
    items: &mut [X],
    job: J,
) where
    J: Fn(usize, &mut [X]) + Sync,
{
    let chunks = if count < min_rows { 1 } else { BANDS };
    let mut jobs = Jobs::new();
    let (mut rest, job) = (&mut items[..count * per], &job);
    for c in 0..chunks {
        let (k0, k1) = (count * c / chunks, count * (c + 1) / chunks);
        let (chunk, tail) = core::mem::take(&mut rest).split_at_mut((k1 - k0) * per);
        rest = tail;
        let _ = jobs.push(move || job(k0, chunk));
    }
    run_all(par, &mut jobs);
}

/// Runs `job(t)` for every band of `n` rows through `par`; the results in band order
/// (`None` past the last band).
pub(crate) fn map_bands<R: Send, J>(par: &dyn Parallel, n: usize, job: J) -> [Option<R>; BANDS]
where
    J: Fn(usize) -> R + Sync,
{
    let mut results: [Option<R>; BANDS] = core::array::from_fn(|_| None);
    {
        let mut jobs = Jobs::new();
        let job = &job;
        for (t, result) in results.iter_mut().take(bands(n)).enumerate() {
            let _ = jobs.push(move || *result = Some(job(t)));
        }
        run_all(par, &mut jobs);
    }
    results
}

/// The second round: band `s`'s rows of `y` gain the partial sums of the bands below it,
/// in band order.
pub(crate) fn reduce<T: Real>(n: usize, y: &mut [T::V3], z: &[T::V3], par: &dyn Parallel) {
    let k = bands(n);
    if k == 1 {
        return;
    }
    let mut jobs = Jobs::new();
    let mut rest = y;
    for s in 0..k {
        let (b0, b1) = (band_start(n, s), band_start(n, s + 1));
        let (ys, tail) = rest.split_at_mut(b1 - b0);
        rest = tail;
        let _ = jobs.push(move || {
            let mut offset = 0;
            for t in 1..k {
                let len = band_start(n, t);
                if t > s {
                    let zt = &z[offset + b0..offset + b1];
                    for (yk, &zk) in ys.iter_mut().zip(zt) {
                        *yk += zk;
                    }
                }
                offset += len;
            }
        });
    }
    run_all(par, &mut jobs);
}

/// Hands every band its rows of `out` (packed, the first `start(i)` entries holding
/// rows `0..i`; or nothing when `out` is empty),
/// of `y` (or nothing) and its partial-sum slice of `z` (or nothing), runs
/// `job(t, rows, y_t, z_t)` for every band through `par`, and returns the first error
/// in band order (the one a single pass in row order meets first).
pub(crate) fn by_bands<T: Real, X: Send, E: Send, J>(
    par: &dyn Parallel,
    n: usize,
    out: &mut [X],
    start: fn(usize) -> usize,
    y: &mut [T::V3],
    z: &mut [T::V3],
    job: J,
) -> Result<(), E>
where
    J: Fn(usize, &mut [X], &mut [T::V3], &mut [T::V3]) -> Result<(), E> + Sync,
{
    let job =
        |t, rows: &mut [X], _: &mut [X], yt: &mut [T::V3], zt: &mut [T::V3]| job(t, rows, yt, zt);
    by_bands_and::<T, X, X, E, _>(par, n, (out, start), (&mut [], start), y, z, job)
}

/// A packed output (of blocks `X`) and the entry its row `i` starts at.
pub(crate) type Packed<'a, X> = (&'a mut [X], fn(usize) -> usize);

/// [`by_bands`] with a second packed output, `side`, of which each band gets its rows
/// too: `job(t, rows, side_rows, y_t, z_t)`.
pub(crate) fn by_bands_and<T: Real, X: Send, S: Send, E: Send, J>(
    par: &dyn Parallel,
    n: usize,
    out: Packed<'_, X>,
    side: Packed<'_, S>,
    y: &mut [T::V3],
    z: &mut [T::V3],
    job: J,
) -> Result<(), E>
where
    J: Fn(usize, &mut [X], &mut [S], &mut [T::V3], &mut [T::V3]) -> Result<(), E> + Sync,
{
    let job =
        |t, rows: &mut [X], side: &mut [S], [yt]: [&mut [T::V3]; 1], [zt]: [&mut [T::V3]; 1]| {
            job(t, rows, side, yt, zt)
        };
    by_bands_k::<T, X, S, E, _, 1>(par, n, out, side, [y], [z], job)
}

/// [`by_bands_and`] for `K` products at once: every band gets its rows of each of the
/// `K` outputs `y` and its partial-sum slice of each of the `K` scratches `z` (each
/// empty, or as [`by_bands`] cuts it).
pub(crate) fn by_bands_k<T: Real, X: Send, S: Send, E: Send, J, const K: usize>(
    par: &dyn Parallel,
    n: usize,
    (out, start): Packed<'_, X>,
    (side, side_start): Packed<'_, S>,
    y: [&mut [T::V3]; K],
    z: [&mut [T::V3]; K],
    job: J,
) -> Result<(), E>
where
    J: Fn(usize, &mut [X], &mut [S], [&mut [T::V3]; K], [&mut [T::V3]; K]) -> Result<(), E> + Sync,
{
    let k = bands(n);
    let mut results: [Option<Result<(), E>>; BANDS] = core::array::from_fn(|_| None);
    {
        let mut jobs = Jobs::new();
        let (mut os, mut ss, mut ys, mut zs) = (out, side, y, z);
        let job = &job;
        for (t, result) in results.iter_mut().take(k).enumerate() {
            let (b0, b1) = (band_start(n, t), band_start(n, t + 1));
            // Slices given empty stay empty for every band.
            let rows = |empty: bool, f: fn(usize) -> usize| match empty {
                true => 0,
                false => f(b1) - f(b0),
            };
            let (lo, ls) = (rows(os.is_empty(), start), rows(ss.is_empty(), side_start));
            let (ot, rest) = core::mem::take(&mut os).split_at_mut(lo);
            os = rest;
            let (st, rest) = core::mem::take(&mut ss).split_at_mut(ls);
            ss = rest;
            let mut yt = cut::<T, K>(&mut ys, b1 - b0);
            let mut zt = cut::<T, K>(&mut zs, b0);
            let _ = jobs.push(move || {
                let (yt, zt) = (
                    yt.each_mut().map(|s| &mut **s),
                    zt.each_mut().map(|s| &mut **s),
                );
                *result = Some(job(t, ot, st, yt, zt));
            });
        }
        run_all(par, &mut jobs);
    }
    for r in results.into_iter().take(k) {
        r.unwrap_or(Ok(()))?;
    }
    Ok(())
}

/// The first `len` entries of each non-empty slice of `v` (which keeps the rest).
fn cut<'a, T: Real, const K: usize>(
    v: &mut [&'a mut [T::V3]; K],
    len: usize,
) -> [&'a mut [T::V3]; K] {
    core::array::from_fn(|q| {
        let s = core::mem::take(&mut v[q]);
        let (head, rest) = s.split_at_mut(if s.is_empty() { 0 } else { len });
        v[q] = rest;
        head
    })
}
