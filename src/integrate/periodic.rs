//! The mobility of a step in a periodic box (feature `periodic`): the Ewald sums of
//! `mobility::periodic` with parameters derived once per step.
//!
//! `xi` and the cutoffs come from the box and the step's largest radius by
//! [`Ewald::new`], once, in the step's checks (`check_periodic`), and every product,
//! assembly and matrix-free metric block of the step reads that one copy
//! ([`super::stages::Sums`]): they depend on the box and the radii only, which a step
//! does not change. Not held in the parameters: the largest radius is the state's (a
//! radius above a stored one would be refused) and `Params` stays small and `Copy`.
//! The assembly and the products run in the bands of [`crate::parallel`] (each block
//! summed on its own, so the same bits on any number of threads); so does the
//! matrix-free product's real-space half ([`periodic::free_product`]).

use crate::cell::Periodic;
use crate::error::StepError;
use crate::linalg::{MobMut, with_blocks};
use crate::mobility::periodic::{self, Ewald};
#[cfg(feature = "pse")]
use crate::mobility::pse::{Pse, PseSize, PseStorage};
use crate::mobility::sums::BoxSums;
#[cfg(feature = "pse")]
use crate::mobility::sums::PseStep;
use crate::noise::reduced;
use crate::parallel::Parallel;
use crate::params::Params;
use crate::real::Real;

/// What a step in a box holds for its products ([`super::stages::Sums`] borrows it):
/// the Ewald parameters, or PSE's ([`Params::pse`]).
#[derive(Debug)]
pub(super) enum Held<T: Real> {
    /// The exact Ewald sums.
    Ewald(Ewald<T>),
    /// The PSE fast path.
    #[cfg(feature = "pse")]
    Pse(Pse<T>),
}

/// The largest radius of the step (the sums accept every radius up to it).
fn a_max<T: Real>(radius: &[T]) -> T {
    radius.iter().fold(T::ZERO, |m, &a| m.max(a))
}

/// The PSE parameters of this box, these spheres and the tolerance `tol`.
#[cfg(feature = "pse")]
pub(super) fn pse<T: Real>(cell: Periodic<T>, radius: &[T], tol: f64) -> Result<Pse<T>, StepError> {
    Ok(Pse::new(cell, a_max(radius), tol)?)
}

/// The PSE storage a step of these spheres needs with `p`
/// ([`Workspace::with_pse`](crate::Workspace::with_pse)): `Some` where the step sums
/// its box by PSE ([`Params::pse`], a box whose images interact), from the same
/// parameters the step derives; `None` where it needs none. A host sizes its arrays
/// with it before the first step (the radii do not change during a run).
#[cfg(feature = "pse")]
pub fn pse_storage<T: Real>(p: &Params<T>, radius: &[T]) -> Result<Option<PseSize>, StepError> {
    match (super::stages::ewald_cell(p), p.pse) {
        (Some(c), Some(tol)) => Ok(Some(pse(c, radius, tol)?.storage(radius.len()))),
        _ => Ok(None),
    }
}

/// The Ewald parameters for this box and these spheres (every radius at most the
/// largest, so the sums accept each one).
pub(super) fn ewald<T: Real>(cell: Periodic<T>, radius: &[T]) -> Result<Ewald<T>, StepError> {
    Ok(Ewald::new(cell, a_max(radius))?)
}

/// `u = mu_tt f` in the box: `mu_tt` assembled into the packed lower triangle `mu`
/// ([`periodic::assemble`]: the blocks of [`periodic::assemble_tt`]), then applied,
/// both in bands through `par` (`bands`: the product's partial sums). With `copy`
/// each row of `mu` is also packed into the compact `f32` copy
/// ([`Params::compact_products`], `noise::reduced`) as soon as it is written, while
/// its blocks are in cache (the Ewald sums cost far more than the packing, so no pass
/// of its own). The product reads the `f64` blocks either way: the unconstrained move
/// keeps its bits.
pub(super) fn assemble_apply<T: Real>(
    p: &Params<T>,
    ew: &Ewald<T>,
    (pos, radius): (&[T::V3], &[T]),
    mu: MobMut<'_, T>,
    (f, u): (&[T::V3], &mut [T::V3]),
    (par, bands): (&dyn Parallel, &mut [T::V3]),
    copy: Option<&mut [T::M3]>,
) -> Result<(), StepError> {
    let eta = p.viscosity;
    with_blocks!(mut mu, mu => {
        match copy {
            None => periodic::assemble(par, ew, eta, pos, radius, mu)?,
            Some(copy) => {
                let side = (copy, reduced::copy_start as fn(usize) -> usize);
                let pack = reduced::pack_rows::<T, _>;
                periodic::assemble_then(par, ew, eta, pos, radius, mu, side, pack)?
            }
        }
        crate::parallel::product::<T>(par, mu, pos.len(), f, u, bands);
        Ok(())
    })
}

/// The caller's PSE arrays as the step's storage, after checking them against the
/// step's PSE parameters (`None` where the step sums by Ewald or has no box).
#[cfg(feature = "pse")]
pub(super) fn pse_store<'a, T: Real>(
    held: Option<&'a Held<T>>,
    n: usize,
    (complex, index, vectors): crate::workspace::PseSlices<'a, T>,
    par: &'a dyn crate::parallel::Parallel,
) -> Result<Option<PseStep<'a, T>>, StepError> {
    let Some(Held::Pse(pse)) = held else {
        return Ok(None);
    };
    let need = pse.storage(n);
    if complex.len() < need.complex || index.len() < need.index || vectors.len() < need.vectors {
        return Err(crate::mobility::pse::PseError::Storage {
            need: [need.complex, need.index, need.vectors],
            have: [complex.len(), index.len(), vectors.len()],
        }
        .into());
    }
    let store = PseStorage::new(complex, index, vectors).with_parallel(par);
    Ok(Some(PseStep::new(pse, store)))
}

/// The step's sums ([`super::stages::Sums`]) over what its checks hold and, for PSE,
/// the storage [`pse_store`] made.
#[cfg(feature = "pse")]
pub(super) fn sums<'a, T: Real>(
    held: Option<&'a Held<T>>,
    store: Option<&'a PseStep<'_, T>>,
) -> super::stages::Sums<'a, T> {
    match (held?, store) {
        (Held::Ewald(e), _) => Some(BoxSums::Ewald(e)),
        (Held::Pse(_), Some(s)) => Some(BoxSums::Pse(s)),
        // `pse_store` makes the storage for every PSE step.
        (Held::Pse(_), None) => None,
    }
}

/// The step's sums ([`super::stages::Sums`]): Ewald's (no `pse` feature).
#[cfg(not(feature = "pse"))]
pub(super) fn sums<T: Real>(held: Option<&Held<T>>) -> super::stages::Sums<'_, T> {
    match held? {
        Held::Ewald(e) => Some(BoxSums::Ewald(e)),
    }
}

#[cfg(test)]
mod tests {
    // The mobility of 512 spheres takes 6 MB: on the heap, which tests have.
    extern crate std;
    use super::{assemble_apply, ewald};
    use crate::cell::Periodic;
    use crate::linalg::{MobMut, Sym, tri};
    use crate::mobility::Hydro;
    use crate::noise::reduced;
    use crate::parallel::{self, Serial, band_scratch};
    use crate::params::Params;
    use crate::real::Real;
    use glam::DVec3;
    use std::{vec, vec::Vec};

    /// Largest entry of `a - b` over the largest entry of `b`.
    fn gap(a: &[DVec3], b: &[DVec3]) -> f64 {
        let top = |v: &[DVec3]| v.iter().fold(0.0, |m: f64, x| m.max(x.abs().max_element()));
        let d: Vec<DVec3> = a.iter().zip(b).map(|(x, y)| *x - *y).collect();
        top(&d) / top(b)
    }

    /// The compact copy a box's assembly writes (`Params::compact_products`): every
    /// product from it agrees with the `f64` product of the stored Ewald blocks to
    /// `f32` rounding (`~1e-7` relative: 1.9 to 4.3e-7 measured, the bound 1e-6), and
    /// writing it changes neither the blocks nor the product the pass computes. The
    /// `f64` products are the reference (the compact path computed none of them); the
    /// free-space mobility of the same spheres gives products off by 0.46 to 15 times
    /// the box's (which removes the mean flow), so a copy of the wrong blocks would fail
    /// by far.
    /// 512 spheres (sixteen bands, two column tiles of the copy) on a jittered 8^3
    /// lattice of spacing 3 filling a box of edge 24 (radii 0.8 to 1, volume fraction 0.12:
    /// images at every distance).
    #[test]
    fn a_boxs_compact_copy_gives_its_products_to_f32_rounding() {
        let (n, l) = (512, 24.0);
        let pos: Vec<DVec3> = (0..n)
            .map(|k| {
                let site = DVec3::new((k % 8) as f64, ((k / 8) % 8) as f64, (k / 64) as f64);
                let t = k as f64;
                let jitter = DVec3::new((1.3 * t).sin(), (0.7 * t).cos(), (2.1 * t).sin());
                3.0 * site + 1.5 + 0.2 * jitter
            })
            .collect();
        let radius: Vec<f64> = (0..n).map(|i| 0.8 + 0.05 * (i % 5) as f64).collect();
        let f: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new((i as f64).sin(), 0.5, (0.3 * i as f64).cos()))
            .collect();
        let cell = Periodic::new([l; 3]).unwrap();
        let mut p = Params::<f64>::new(0.01);
        p.periodic = Some(cell);
        let ew = ewald(cell, &radius).unwrap();
        let mut bands = vec![DVec3::ZERO; band_scratch(n)];
        let spheres = (&pos[..], &radius[..]);
        // The pass without and with the copy.
        let (mut plain, mut packed): (Vec<Sym<f64>>, Vec<Sym<f64>>) =
            (vec![[0.0; 6]; tri(n)], vec![[0.0; 6]; tri(n)]);
        let (mut u_plain, mut u_packed) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
        let mu = MobMut::Sym(&mut plain);
        let work = (&Serial as &dyn parallel::Parallel, &mut bands[..]);
        assemble_apply(&p, &ew, spheres, mu, (&f, &mut u_plain), work, None).unwrap();
        let mu = MobMut::Sym(&mut packed);
        let (work, side) = ((&Serial as _, &mut bands[..]), Some(&mut copy[..]));
        assemble_apply(&p, &ew, spheres, mu, (&f, &mut u_packed), work, side).unwrap();
        let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
            v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
        };
        assert_eq!(bits(&u_packed), bits(&u_plain));
        assert!(
            packed
                .iter()
                .zip(&plain)
                .all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits))
        );
        // The free-space mobility of the same spheres, to show what a wrong copy gives.
        let mut free: Vec<Sym<f64>> = vec![[0.0; 6]; tri(n)];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut free).unwrap();
        let mut worst: f64 = 0.0;
        for q in 0..4 {
            let x: Vec<DVec3> = (0..n)
                .map(|i| {
                    let t = (i * (q + 1)) as f64;
                    DVec3::new((0.37 * t).sin(), (0.11 * t).cos(), 1.0 - q as f64 * 0.5)
                })
                .collect();
            let (mut exact, mut compact, mut open) = (
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
                vec![DVec3::ZERO; n],
            );
            parallel::product::<f64>(&Serial, &packed, n, &x, &mut exact, &mut bands);
            reduced::apply::<f64>(&Serial, &copy, n, &x, &mut compact, &mut bands);
            parallel::product::<f64>(&Serial, &free, n, &x, &mut open, &mut bands);
            let (g, wrong) = (gap(&compact, &exact), gap(&open, &exact));
            assert!(g < 1e-6, "vector {q}: compact vs f64 {g:e}");
            assert!(wrong > 0.1, "vector {q}: free space vs box only {wrong:e}");
            worst = worst.max(g);
        }
        std::eprintln!("box, N = {n}: compact vs f64 products, largest relative gap {worst:.2e}");
    }
}
