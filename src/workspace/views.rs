//! The workspace carved into the named slices one step uses. Each method takes only
//! its own parts (the others are empty), in the order [`Layout`] counts them.

use super::{Layout, Workspace};
use crate::bonds::Bond;
use crate::constraints::Scratch;
use crate::constraints::{SolverKind, index_scratch, krylov_scratch_per_bond};
use crate::error::StepError;
use crate::linalg::{MobMut, tri};
use crate::noise::lanczos::{scalars as lanczos_scalars, vectors as lanczos_vectors};
use crate::parallel::{Parallel, band_scratch};
use crate::params::{Method, Params};
use crate::real::Real;

/// Named slices for one step of `n` particles, `nb` bonds, `m` block rows.
pub(crate) struct Views<'a, T: Real> {
    /// The stored mobility (symmetric blocks in free space, [`super::symmetric`]).
    pub mu: MobMut<'a, T>,
    /// A second stored mobility (as `mu`): `Overdamped2`'s at the predicted point, or
    /// the Brownian midpoint's by Lanczos noise (by Cholesky it takes the factor's
    /// blocks, `integrate::brownian`).
    pub mu2: MobMut<'a, T>,
    pub fac: &'a mut [T::M3],
    pub disp: &'a mut [T::V3],
    pub force: &'a mut [T::V3],
    pub work_a: &'a mut [T::V3],
    pub work_b: &'a mut [T::V3],
    pub work_c: &'a mut [T::V3],
    pub grad: &'a mut [T::V3],
    pub grad_new: &'a mut [T::V3],
    pub lambda: &'a mut [T],
    pub kappa: &'a mut [T],
    pub inv_mass: &'a mut [T],
    pub sqrt_m: &'a mut [T],
    pub new_pos: &'a mut [T::V3],
    pub new_vel: &'a mut [T::V3],
    pub new_omega: &'a mut [T::V3],
    pub scratch: Scratch<'a, T>,
    /// The Lanczos basis and its scalars (thermal steps by Lanczos only).
    pub basis: &'a mut [T::V3],
    pub krylov_t: &'a mut [T],
    /// Bonds then contacts (steps with contacts only; empty otherwise), and the
    /// contacts' pair search's cell list.
    pub links: Links<'a, T>,
    /// How the mobility's bands run ([`Workspace::with_parallel`]).
    pub par: &'a dyn Parallel,
    /// The stored `mu_tt` product's band partial sums ([`band_scratch`]).
    pub bands: &'a mut [T::V3],
    /// The caller's fast products' arrays ([`Workspace::with_pse`], `Workspace::with_fast`).
    #[cfg(feature = "pse")]
    pub pse: super::PseSlices<'a, T>,
    /// The near field's packed far-field grand mobility and its dense Stokesian
    /// dynamics mobility ([`Params::near`]; empty without).
    pub near: (&'a mut [T::M3], &'a mut [T]),
    /// The iterative near field's vectors and indices ([`Params::near`] with
    /// [`Params::matrix_free`]; empty otherwise): `near` then holds the far field's
    /// packed grand mobility and the close pairs' scalars.
    #[cfg_attr(not(feature = "near"), allow(dead_code))]
    pub near_iter: (&'a mut [T::V3], &'a mut [usize]),
}

/// The storage of the one-sided constraints (contacts, wall links): the link list
/// (bonds, then contacts) and the contacts' pair search's cell list
/// ([`crate::cell_list::indices`] indices; empty below its threshold).
pub(crate) struct Links<'a, T: Real> {
    /// Bonds then contacts ([`Layout::links`]; empty without contacts or a wall).
    pub list: &'a mut [Bond<T>],
    /// The cell list's indices (only with the `cells` feature: firmware's projection
    /// takes the link list alone, as before).
    #[cfg(feature = "cells")]
    pub cells: &'a mut [usize],
}

impl<'a, T: Real> Links<'a, T> {
    /// The same storage, borrowed for a shorter time (a second projection).
    pub fn reborrow(&mut self) -> Links<'_, T> {
        Links {
            list: &mut *self.list,
            #[cfg(feature = "cells")]
            cells: &mut *self.cells,
        }
    }

    /// The link list and the cell list's indices (none without the `cells` feature).
    pub fn split(self) -> (&'a mut [Bond<T>], &'a mut [usize]) {
        #[cfg(feature = "cells")]
        return (self.list, self.cells);
        #[cfg(not(feature = "cells"))]
        return (self.list, &mut []);
    }
}

/// Takes slices off the front of a slice.
struct Carve<'a, X>(&'a mut [X]);

impl<'a, X> Carve<'a, X> {
    /// The next `k` elements (the layout check guarantees they exist).
    fn take(&mut self, k: usize) -> &'a mut [X] {
        let rest = core::mem::take(&mut self.0);
        let (head, tail) = rest.split_at_mut(k.min(rest.len()));
        self.0 = tail;
        head
    }
}

impl<T: Real> Workspace<'_, T> {
    /// Checks that the layout of this step fits, then splits the storage. Every
    /// per-constraint slice holds the bonds and, with contacts, the contact capacity.
    pub(crate) fn views(
        &mut self,
        p: &Params<T>,
        n: usize,
        bonds: usize,
    ) -> Result<Views<'_, T>, StepError> {
        let (method, rotation, kind) = (p.method, p.rotation, p.solver_kind(n, bonds));
        let need = Layout::for_params(p, n, bonds);
        let have = self.capacity();
        if !have.holds(&need) {
            return Err(StepError::Storage { need, have });
        }
        let nb = p.constraints(n, bonds);
        let links = Carve(&mut *self.links).take(need.links);
        let m = super::block_rows(method, rotation, n);
        let krylov = matches!(kind, SolverKind::Krylov);
        let mut bl = Carve(&mut *self.blocks);
        let mut ve = Carve(&mut *self.vectors);
        let mut sc = Carve(&mut *self.scalars);
        let mut ix = Carve(&mut *self.indices);
        // Multipliers first: `Workspace::multipliers` reads them there.
        let lambda = sc.take(nb);
        let (new_pos, new_vel, new_omega) = (ve.take(n), ve.take(n), ve.take(n));
        let (force, grad) = (ve.take(m), ve.take(nb));
        // (The iterative near field stores no mobility, whatever the method.)
        let iterative = super::layout::near_iterative(p);
        let unstored = p.matrix_free
            && matches!(
                method,
                Method::Overdamped | Method::Overdamped2 | Method::Springs
            );
        let stored = !(unstored || iterative);
        // The dense solvers' table of displacements (see `Layout::with_solver`).
        // (The iterative near field's sweep and Newton read one too: `near_iter`.)
        let table = if krylov || !(stored || iterative) {
            0
        } else {
            n * nb
        };
        // Thermal noise (`Layout::thermal`): the factor, one vector array, the midpoint's
        // bond vectors and multipliers.
        // (The iterative near field's noise has storage of its own, in `near_iter`.)
        let thermal = p.brownian.is_some() && !iterative;
        let lanczos =
            thermal && matches!(method, Method::Overdamped | Method::Springs) && p.lanczos_noise(n);
        let uncorrected =
            matches!(p.brownian, Some(b) if b.drift == crate::params::Drift::Uncorrected);
        let (mats, work, extra_bonds, inv_mass, sqrt_m, disp) = match method {
            Method::Overdamped if thermal => (2, [n, n, 0], nb, 0, 0, table),
            Method::Overdamped => (1, [n, 0, 0], 0, 0, 0, table),
            Method::Springs if thermal => (2, [n, n, 0], 0, 0, 0, 0),
            Method::Springs => (1, [n, 0, 0], 0, 0, 0, 0),
            Method::Overdamped2 => (2, [n, n, n], nb, 0, 0, table),
            Method::Rattle => (2, [n, n, n], nb, n, 0, 0),
            Method::RattleStable => (2, [m, m, 0], nb, 0, m, table),
        };
        // The stored mobilities: symmetric blocks of six scalars in free space, else
        // blocks of nine (`Layout::for_params`).
        let second = matches!(method, Method::Overdamped2);
        let midpoint = lanczos && stored && !uncorrected;
        let (one, two) = (
            if stored { tri(m) } else { 0 },
            if (second && stored) || midpoint {
                tri(m)
            } else {
                0
            },
        );
        // (`as_chunks_mut`, Rust 1.88: the kernel's minimum since this storage.)
        use super::layout::SYM;
        let (mu, mu2) = if super::symmetric(p) {
            let mut sym = |k: usize| MobMut::Sym(sc.take(SYM * k).as_chunks_mut::<SYM>().0);
            (sym(one), sym(two))
        } else {
            (MobMut::Full(bl.take(one)), MobMut::Full(bl.take(two)))
        };
        // The Cholesky factor of the noise (Lanczos needs none).
        let factor = mats == 2 && !second && !lanczos;
        // The compact copy of the mobility lives where a factor would
        // (`Params::compact_products`: first-order Overdamped without noise, no factor;
        // the Lanczos noise's reduced copy, `noise::reduced::for_noise`).
        let compact = p.compact_copy(n, bonds) || crate::noise::reduced::for_noise(p, n);
        let fac = bl.take(match (factor, compact) {
            (true, _) => tri(m),
            (false, true) => crate::noise::reduced::slots(n),
            (false, false) => 0,
        });
        let (work_a, work_b, work_c) = (ve.take(work[0]), ve.take(work[1]), ve.take(work[2]));
        let grad_new = ve.take(extra_bonds);
        let kappa = sc.take(extra_bonds);
        let inv_mass = sc.take(inv_mass);
        let sqrt_m = sc.take(sqrt_m);
        let disp = ve.take(disp);
        // Stored or matrix-free, the products sum in bands (`parallel::free_product`).
        // (`Overdamped2` only matrix-free: its stored products are serial.)
        let banded = matches!(method, Method::Overdamped | Method::Springs)
            || (method == Method::Overdamped2 && unstored && !iterative);
        let bands = ve.take(if banded { band_scratch(n) } else { 0 });
        let constrained = !matches!(method, Method::Springs);
        let newton = constrained && matches!(kind, SolverKind::Newton);
        let scratch = Scratch {
            jac: sc.take(if newton { nb * nb } else { 0 }),
            rhs: sc.take(if newton { nb } else { 0 }),
            piv: ix.take(match (constrained, kind) {
                (true, SolverKind::Newton | SolverKind::Krylov) => index_scratch(kind, n, nb),
                _ => 0,
            }),
            krylov: sc.take(if constrained && krylov {
                krylov_scratch_per_bond() * nb
            } else {
                0
            }),
            beads: ve.take(if constrained && krylov {
                2 * n + 2 * m + band_scratch(m)
            } else {
                0
            }),
            par: self.parallel,
            carry: Default::default(),
        };
        #[cfg(feature = "cells")]
        let cells = ix.take(crate::cell_list::indices(n));
        let cap = p.lanczos.max_iterations as usize;
        let basis = ve.take(if lanczos { lanczos_vectors(cap, n) } else { 0 });
        let krylov_t = sc.take(if lanczos { lanczos_scalars(cap) } else { 0 });
        let [noise_v, noise_s] = super::layout::near_noise_sizes(p, n);
        let near = match p.near_on() {
            true if iterative => {
                let [b, _, s, _] =
                    super::layout::near_iterative_sizes(n, nb, !super::layout::near_far_product(p));
                (bl.take(b), sc.take(s + noise_s))
            }
            true => (
                bl.take(super::layout::near_blocks(n)),
                sc.take(super::layout::near_scalars(n, super::layout::near_kept(p))),
            ),
            false => (bl.take(0), sc.take(0)),
        };
        let near_iter = match iterative {
            true => {
                let [_, v, _, i] =
                    super::layout::near_iterative_sizes(n, nb, !super::layout::near_far_product(p));
                (ve.take(v + noise_v), ix.take(i))
            }
            false => (ve.take(0), ix.take(0)),
        };
        Ok(Views {
            mu,
            mu2,
            fac,
            disp,
            force,
            work_a,
            work_b,
            work_c,
            grad,
            grad_new,
            lambda,
            kappa,
            inv_mass,
            sqrt_m,
            new_pos,
            new_vel,
            new_omega,
            scratch,
            basis,
            krylov_t,
            links: Links {
                list: links,
                #[cfg(feature = "cells")]
                cells,
            },
            par: self.parallel,
            bands,
            #[cfg(feature = "pse")]
            pse: (
                &mut *self.pse.0,
                &mut *self.pse.1,
                &mut *self.pse.2,
                &mut *self.pse.3,
            ),
            near,
            near_iter,
        })
    }
}
