//! The geometry as a step sees it: one interface ([`Hydrodynamics`]) through which the
//! stages, the constraint metric and the front ends' mobility reach the hydrodynamics
//! of free space, a wall, or a periodic box (Ewald or PSE sums, [`sums`] with the
//! `periodic` feature). It sits above the geometries themselves (`crate::mobility`:
//! `mobility.rs` with the pair blocks of `rpy.rs` and the bands of `parallel/` for
//! free space, `mobility/wall.rs`, `mobility/periodic.rs`, `mobility/pse.rs`) and the
//! noise, below the constraint solvers and the integrators that read it.
//!
//! **Why a closed enum, not a trait the step is generic over.** The geometry is data in
//! [`Params`](crate::Params) (`wall`, `periodic`, `pse`), chosen at run time by hosts,
//! the Python package and scene files, and the step's public signature has no
//! geometry parameter: a type parameter would change that signature for every caller
//! and need a dispatch from the parameters to one monomorphised step per geometry in
//! every host (each step compiled four times). Firmware drops what it does not use by
//! the kernel's features (`wall`, `periodic`, `pse`: a variant of [`Hydrodynamics`]
//! and its module's `step` compile away with its feature), as before.
//!
//! **What a geometry gives.** Its blocks, not its loops: a source of blocks for the
//! band loops written once in `parallel/source.rs` (`Blocks`: what a row needs of a
//! sphere, the self block, the pair block; the assembly in bands, the matrix-free
//! banded and serial products and the block at `(p, q)` read them) and, with
//! rotation, for the grand mobility and the spins of `mobility/grand.rs` (`Grand`);
//! then, in its own module here ([`free`], [`wall`], [`periodic`]), which of those loops
//! each operation runs and what it refuses: [`Geometry`], for a small struct of what
//! its blocks are evaluated with (`step`, with the geometry's feature), and what its
//! parameters name, for a type of [`Place`]'s (always compiled: the checks refuse a
//! geometry the kernel was built without). [`Hydrodynamics`] holds one of them; its variants,
//! its choice ([`Hydrodynamics::at`]) and the forwarding of every operation are written
//! by the one registration `geometries!` below, a line per geometry, and so are
//! [`Place`]'s variants, its choice ([`Place::new`]) and its forwarding. What the
//! parameters name is asked through [`Place`] ([`Params::place`](crate::Params::place)):
//! the checks, the workspace's sizes, the noise and the minimum images never read
//! the parameters' geometry fields by hand.
//!
//! **Adding a geometry** (a slit between two walls, say; `docs/GEOMETRY.md`): its
//! blocks in a module under `mobility/` (`Blocks`, `Grand`), its [`Geometry`] and its
//! answers to [`Place`]'s questions (its hard surfaces among them, [`Surfaces`]) in a
//! module here, one line of `geometries!`, the parameter that names it (a field of
//! [`Named`], read in `Params::place`), its input checks (a file under
//! `integrate/checks/`, one call in `check_all`), its part of the near field where it
//! has one (a file under `stokesian/`: its far field is its place and sums), its
//! feature, and its tests.

#[cfg(feature = "pse")]
pub mod fast;
pub mod free;
pub mod periodic;
pub mod slit;
#[cfg(feature = "periodic")]
pub mod sums;
pub mod wall;

use core::marker::PhantomData;

use crate::error::StepError;
use crate::linalg::MobMut;
use crate::mobility::Hydro;
use crate::parallel::Parallel;
use crate::real::Real;

/// The step's periodic sums ([`sums::BoxSums`]: Ewald, or PSE with
/// [`Params::pse`](crate::Params::pse)): `Some` in a periodic box whose images interact
/// (not with free draining), derived once by the step's checks and read by every
/// product, assembly and matrix-free metric of the step.
#[cfg(feature = "periodic")]
pub type Sums<'a, T> = Option<sums::BoxSums<'a, T>>;
/// The step's periodic sums: none without the `periodic` feature (always `None`).
#[cfg(not(feature = "periodic"))]
pub type Sums<'a, T> = Option<&'a PhantomData<T>>;

/// The step's sums that have blocks, as the near field's far field holds them
/// (`crate::stokesian::Far`): the Ewald sums, not PSE's products and storage, so that
/// it is `Send` and `Sync`; from [`Sums`] by `TryFrom`, back by `From`.
#[cfg(feature = "periodic")]
pub type BlockSums<'a, T> = Option<sums::Blocks<'a, T>>;
/// The step's sums that have blocks: none without the `periodic` feature.
#[cfg(not(feature = "periodic"))]
pub type BlockSums<'a, T> = Sums<'a, T>;

/// What the step's checks derive once and hold for [`Sums`] to borrow (the box's Ewald
/// or PSE parameters, the fast free-space product's: `periodic/held.rs`).
#[cfg(feature = "periodic")]
pub(crate) type HeldSums<T> = Option<periodic::held::Held<T>>;
/// What the step's checks hold for [`Sums`] to borrow: nothing without the feature.
#[cfg(not(feature = "periodic"))]
pub(crate) type HeldSums<T> = Option<PhantomData<T>>;

#[cfg(feature = "periodic")]
pub(crate) use periodic::held::{Held, held_ewald, step_sums};
#[cfg(feature = "pse")]
pub(crate) use periodic::held::{PseSize, fast_store, pse_size};

/// The Ewald sums of what the step's checks hold: nothing to hold without the
/// `periodic` feature.
#[cfg(not(feature = "periodic"))]
pub(crate) fn held_ewald<T: Real>(held: &HeldSums<T>) -> Sums<'_, T> {
    held.as_ref()
}

/// Whether a geometry this kernel was built with has pair blocks that are not
/// symmetric (the wall's: block `(j, i)` is the transpose of `(i, j)`), so that the
/// readers of a stored nine-scalar mobility must transpose the other triangle. Without
/// one, every such branch folds away.
pub const GENERAL_BLOCKS: bool = cfg!(feature = "wall");

/// Why PSE ([`Params::pse`](crate::Params::pse)) cannot serve a stage that needs the
/// assembled mobility.
pub(crate) const PSE_ASSEMBLED: &str = "PSE (Params::pse) where the step needs the assembled mobility \
     (without matrix_free, Cholesky noise, the Sweep or Newton solver, RattleStable): \
     PSE gives products only";

/// What a geometry gives a step: each geometry's module (`free.rs`, `wall.rs`,
/// `periodic.rs` here) implements it for a small struct of what its blocks are
/// evaluated with, and [`Hydrodynamics`] forwards each call to the one the step runs
/// in. Its blocks come from the band loops written once (`parallel/source.rs`,
/// `mobility/grand.rs`); what a geometry writes here is which of them it runs and what
/// it refuses.
pub trait Geometry<T: Real>: Copy {
    /// `mu_tt(pos)` into the packed lower triangle `mu`, on the calling thread.
    fn assemble_tt(self, pos: &[T::V3], radius: &[T], mu: MobMut<'_, T>) -> Result<(), StepError>;

    /// `u = mu_tt(pos) f` assembled into `mu` and applied, in bands through `par`.
    fn assemble_apply(
        self,
        par: &dyn Parallel,
        spheres: (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        fu: (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError>;

    /// [`Geometry::assemble_apply`] that also writes the compact copy `copy` of `mu`
    /// (symmetric blocks only: a geometry without them refuses it).
    fn assemble_apply_copy(
        self,
        par: &dyn Parallel,
        spheres: (&[T::V3], &[T]),
        mu: MobMut<'_, T>,
        fu: (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
        copy: &mut [T::M3],
    ) -> Result<(), StepError>;

    /// `u = mu_tt(pos) f` matrix-free (`bands`: the scratch of the bands through `par`).
    fn product(
        self,
        par: &dyn Parallel,
        spheres: (&[T::V3], &[T]),
        fu: (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
    ) -> Result<(), StepError>;

    /// The grand mobility (translations then rotations) into `out`.
    fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError>;

    /// `out_i += sum_j rt_ij f_j`: the spins of torque-free spheres.
    fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError>;

    /// The block of `mu_tt` a row-`p` entry of the matrix-free metric reads against
    /// sphere `q` (`None` where there is none).
    fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3>;

    /// Whether the geometry has pair blocks to read.
    #[inline(always)]
    fn has_blocks(self) -> bool {
        true
    }

    /// Whether every block is symmetric, so that a table of the metric reads lower
    /// triangles only.
    #[inline(always)]
    fn symmetric(self) -> bool {
        true
    }

    /// Whether the metric may read only the lower triangles of its blocks because they
    /// are known symmetric in bits without reading them.
    #[inline(always)]
    fn lower_only(self) -> bool {
        false
    }
}

/// Writes the registration below (`Variant(its step's type, its place's type)`) into
/// [`Place`] (a variant a geometry, whatever the features), [`Place::new`] (the first
/// geometry that claims what the parameters name, in the order listed, free space
/// where none does), `each_place!` (a question forwarded to every place),
/// [`Hydrodynamics`] (a variant a geometry, with its feature), [`Hydrodynamics::at`]
/// (the same choice) and `each!` (a call forwarded to every variant). `$d` is a `$`
/// handed in, so that the generated macros can have metavariables of their own.
macro_rules! geometries {
    ($d:tt $(
        $(#[doc = $doc:literal])*
        $(#[cfg($c:meta)])?
        $V:ident($ty:ty, $P:ty),
    )* _ => $(#[doc = $fdoc:literal])* $F:ident($fty:ty, $fP:ty) $(,)?) => {
        /// What a step's parameters name ([`Params::place`](crate::Params::place)),
        /// before the kernel's features are applied (the checks refuse a geometry the
        /// kernel was built without, and a box with a wall): one variant a geometry,
        /// each answering in its own module what the checks, the workspace's sizes, the
        /// noise and the minimum images ask (`place.rs` forwards).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Place<T: Real> {
            $($(#[doc = $doc])* $V($P),)*
            $(#[doc = $fdoc])*
            $F($fP),
        }

        impl<T: Real> Place<T> {
            /// The place of what the parameters name: the first registered geometry
            /// that claims it, in the order listed, free space where none does.
            #[inline(always)]
            pub const fn new(named: Named<T>) -> Self {
                $(
                    if let Some(g) = <$P>::claims(named) {
                        return Self::$V(g);
                    }
                )*
                Self::$F(<$fP>::new())
            }
        }

        /// `$e` with `$g` bound to what the parameters name of the place `$s`,
        /// whichever geometry it is.
        macro_rules! each_place {
            ($d s:expr, $d g:ident => $d e:expr) => {
                match $d s {
                    $(Place::$V($d g) => $d e,)*
                    Place::$F($d g) => $d e,
                }
            };
        }

        /// The hydrodynamics of the geometry a step runs in, with the level and
        /// viscosity its blocks are evaluated at: one variant a geometry, each
        /// implementing [`Geometry`] in its own module.
        #[derive(Clone, Copy, Debug)]
        pub enum Hydrodynamics<'a, T: Real> {
            $($(#[doc = $doc])* $(#[cfg($c)])? $V($ty),)*
            $(#[doc = $fdoc])*
            $F($fty),
            /// Never built: holds the lifetime where no variant borrows (without the
            /// `periodic` feature), so that the variants need no twin without it.
            #[doc(hidden)]
            Never(core::convert::Infallible, PhantomData<&'a T>),
        }

        impl<'a, T: Real> Hydrodynamics<'a, T> {
            /// The geometry of a step at `place` ([`Params::place`](crate::Params::place))
            /// with its sums: the first registered geometry that claims them, free space
            /// where none does. What the stages build, so that a new geometry reaches
            /// them through [`Place`] and its registration alone.
            #[inline(always)]
            pub fn at(place: Place<T>, level: Hydro, eta: T, sums: Sums<'a, T>) -> Self {
                $(
                    $(#[cfg($c)])?
                    if let Some(g) = <$ty>::at(place, level, eta, sums) {
                        return Self::$V(g);
                    }
                )*
                let _ = (place, sums); // Read above only with the geometries' features.
                Self::$F(<$fty>::new(level, eta))
            }

            /// Free space's blocks whatever the place: what a metric takes as its
            /// preconditioner's blocks where the far field itself is a fast product.
            #[inline(always)]
            pub fn free_space(level: Hydro, eta: T) -> Self {
                Self::$F(<$fty>::new(level, eta))
            }
        }

        /// `$e` with `$g` bound to the geometry of the step `$s`, whichever it is.
        macro_rules! each {
            ($d s:expr, $d g:ident => $d e:expr) => {
                match $d s {
                    $($(#[cfg($c)])? Hydrodynamics::$V($d g) => $d e,)*
                    Hydrodynamics::$F($d g) => $d e,
                    Hydrodynamics::Never(never, _) => match never {},
                }
            };
        }
    };
}

// The registration: every geometry once, in the order the choice tries them.
geometries! {$
    /// Between two walls (`mobility/slit.rs`; feature `slit`).
    #[cfg(feature = "slit")]
    Slit(slit::step::Slit<T>, slit::Between<T>),
    /// In a periodic box; its step where its images interact, with the step's sums
    /// (Ewald, `mobility/periodic.rs`, or PSE, `mobility/pse.rs`; feature `periodic`).
    #[cfg(feature = "periodic")]
    Periodic(periodic::step::Periodic<'a, T>, periodic::InBox<T>),
    /// Above a no-slip wall (`mobility/wall.rs`; feature `wall`).
    #[cfg(feature = "wall")]
    Wall(wall::step::Wall<T>, wall::Above<T>),
    // Where no other geometry claims the place:
    _ =>
    /// Free space (`mobility.rs`; the bands of `parallel/`).
    Free(free::Free<T>, free::Anywhere),
}

mod place;
pub mod surface;

pub use place::Named;
pub use surface::{Surface, Surfaces};

impl<'a, T: Real> Hydrodynamics<'a, T> {
    /// The geometry of a step: in the box when it has sums, above the wall at `wall`
    /// (with the kernel's `wall` feature; without it the wall's code compiles away),
    /// free space otherwise.
    #[inline(always)]
    pub fn new(level: Hydro, eta: T, wall: Option<T>, sums: Sums<'a, T>) -> Self {
        Self::at(
            Place::new(Named {
                wall,
                ..Named::FREE
            }),
            level,
            eta,
            sums,
        )
    }

    /// `mu_tt(pos)` into the packed lower triangle `mu`, on the calling thread.
    pub fn assemble_tt(
        self,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
    ) -> Result<(), StepError> {
        each!(self, g => g.assemble_tt(pos, radius, mu))
    }

    /// `u = mu_tt(pos) f` assembled into `mu` and applied, in bands through `par`
    /// (`bands` holds their partial sums, [`crate::parallel`]).
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_apply(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
        f: &[T::V3],
        u: &mut [T::V3],
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        each!(self, g => g.assemble_apply(par, (pos, radius), mu, (f, u), bands))
    }

    /// [`Hydrodynamics::assemble_apply`] that also writes each row of the compact copy
    /// `copy` of `mu` ([`Params::compact_products`](crate::Params::compact_products),
    /// `noise::reduced`) in the same pass, while the row's blocks are in cache; the
    /// product reads the full blocks, with the same bits. Apart, so that a kernel whose
    /// steps keep no copy (an `f32` firmware) links none of it. Only symmetric blocks
    /// have a copy: above a wall it is refused.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble_apply_copy(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        mu: MobMut<'_, T>,
        (f, u): (&[T::V3], &mut [T::V3]),
        bands: &mut [T::V3],
        copy: &mut [T::M3],
    ) -> Result<(), StepError> {
        each!(self, g => g.assemble_apply_copy(par, (pos, radius), mu, (f, u), bands, copy))
    }

    /// `u = mu_tt(pos) f` matrix-free: every pair block evaluated where it is used. In
    /// free space and above a wall in the bands of the stored product through `par`
    /// (`bands`: their scratch), with its bits; in the box by its sums.
    #[allow(clippy::too_many_arguments)]
    pub fn product(
        self,
        par: &dyn Parallel,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        u: &mut [T::V3],
        bands: &mut [T::V3],
    ) -> Result<(), StepError> {
        each!(self, g => g.product(par, (pos, radius), (f, u), bands))
    }

    /// The grand mobility (`2n x 2n` blocks, translations then rotations, packed as
    /// [`crate::mobility::assemble_grand`] stores it) into `out`.
    pub fn assemble_grand(
        self,
        pos: &[T::V3],
        radius: &[T],
        out: &mut [T::M3],
    ) -> Result<(), StepError> {
        each!(self, g => g.assemble_grand(pos, radius, out))
    }

    /// `out_i += sum_j rt_ij f_j`: the spins of torque-free spheres from the forces `f`
    /// they exert on the fluid (none with free draining in free space).
    pub fn add_spin(
        self,
        pos: &[T::V3],
        radius: &[T],
        f: &[T::V3],
        out: &mut [T::V3],
    ) -> Result<(), StepError> {
        each!(self, g => g.add_spin(pos, radius, f, out))
    }

    /// The block of `mu_tt` a row-`p` entry of the matrix-free metric reads against
    /// sphere `q` (`None` for nested spheres, and always in a PSE box, which has no
    /// blocks: [`Hydrodynamics::has_blocks`]).
    #[inline(always)]
    pub fn block_at(self, pos: &[T::V3], radius: &[T], p: usize, q: usize) -> Option<T::M3> {
        each!(self, g => g.block_at(pos, radius, p, q))
    }

    /// Whether the geometry has pair blocks to read (not PSE, which gives products only).
    #[inline(always)]
    pub fn has_blocks(self) -> bool {
        each!(self, g => g.has_blocks())
    }

    /// Whether every block is symmetric (all but the wall's), so that a table of the
    /// metric reads lower triangles only.
    #[inline(always)]
    pub fn symmetric(self) -> bool {
        each!(self, g => g.symmetric())
    }

    /// Whether the metric may read only the lower triangles of its blocks because they
    /// are known symmetric in bits without reading them (the Ewald box's). Free space's
    /// are too, but its entries read all nine, as they always have: the same bits.
    #[inline(always)]
    pub fn lower_only(self) -> bool {
        each!(self, g => g.lower_only())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{sym_matvec, tri};
    use crate::parallel;
    use glam::DVec3;

    const N: usize = 7;

    /// Spheres of unequal radii, some overlapping, all above a wall at -0.5.
    fn spheres() -> ([DVec3; N], [f64; N], [DVec3; N]) {
        let pos = core::array::from_fn(|k| {
            let t = k as f64;
            DVec3::new(
                1.7 * libm::sin(1.3 * t),
                1.9 * libm::cos(0.7 * t),
                2.0 + 1.1 * t,
            )
        });
        let radius = core::array::from_fn(|k| 0.6 + 0.1 * (k % 3) as f64);
        let f = core::array::from_fn(|k| DVec3::new(libm::sin(k as f64), -0.4, 0.3 * k as f64));
        (pos, radius, f)
    }

    /// The interface's matrix-free product has the bits of its own assembly applied
    /// (the product of the stored blocks), and its metric blocks are the stored ones:
    /// in free space and above a wall, the geometries whose products promise both.
    #[test]
    fn product_and_blocks_agree_with_the_assembly() -> Result<(), StepError> {
        let (pos, radius, f) = spheres();
        let geometries = [
            Hydrodynamics::new(Hydro::Rpy, 0.9, None, None),
            Hydrodynamics::new(Hydro::Oseen, 0.9, None, None),
            #[cfg(feature = "wall")]
            Hydrodynamics::new(Hydro::Rpy, 0.9, Some(-0.5), None),
        ];
        for h in geometries {
            let mut mu = [glam::DMat3::ZERO; tri(N)];
            h.assemble_tt(&pos, &radius, MobMut::Full(&mut mu))?;
            let (mut stored, mut free) = ([DVec3::ZERO; N], [DVec3::ZERO; N]);
            sym_matvec::<f64>(&mu, N, &f, &mut stored);
            h.product(&parallel::Serial, &pos, &radius, &f, &mut free, &mut [])?;
            let bits = |v: &DVec3| v.to_array().map(f64::to_bits);
            assert!(
                free.iter().zip(&stored).all(|(a, b)| bits(a) == bits(b)),
                "{h:?}"
            );
            // Row `j` of the metric reads the block stored at `(i, j)`, `j < i`.
            for i in 0..N {
                for j in 0..i {
                    assert_eq!(
                        h.block_at(&pos, &radius, j, i),
                        Some(mu[tri(i) + j]),
                        "{h:?}"
                    );
                }
            }
        }
        Ok(())
    }

    /// The one choice: the box's sums over the wall over free space, and the wall only
    /// with its feature.
    #[test]
    fn the_geometry_is_chosen_in_one_place() {
        let free = Hydrodynamics::new(Hydro::Rpy, 1.0, None, None);
        assert!(matches!(free, Hydrodynamics::Free(_)));
        let wall = Hydrodynamics::<f64>::new(Hydro::Rpy, 1.0, Some(0.0), None);
        assert_eq!(
            matches!(wall, Hydrodynamics::Free(_)),
            !cfg!(feature = "wall")
        );
    }
}
