//! Step parameters: one plain `Copy` struct with documented defaults.

use crate::cell::Periodic;
use crate::constraints::{Solver, SolverKind};
use crate::mobility::Hydro;
use crate::noise::lanczos::Lanczos;
use crate::real::Real;

/// Stokesian dynamics' near-field parameters ([`Params::near`]).
#[cfg(feature = "near")]
pub use crate::stokesian::NearField;

/// Without the kernel's `near` feature: no near field, and no value of this type
/// ([`Params::near`] is `None`).
#[cfg(not(feature = "near"))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearField<T>(core::convert::Infallible, core::marker::PhantomData<T>);

/// Close pairs a sphere the iterative near field's storage has room for
/// ([`Params::near`] with [`Params::matrix_free`]; [`Layout::for_params`](crate::Layout::for_params)
/// counts `n` times this): 48 is 96 neighbours inside the cutoff, which the default
/// cutoff (4 mean radii) reaches for equal spheres near a volume fraction of 0.45
/// (0.25 has 52). A step with more close pairs is refused
/// ([`StepError::Unsupported`](crate::StepError::Unsupported)), its state unchanged.
pub const NEAR_PAIRS_PER_SPHERE: usize = 48;

/// Which integrator [`step`](crate::integrate::step) runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// HydroSHAKE, first order, inertia dropped: `r' = r + dt (U_inf + mu F) + dt mu G^T lambda`.
    #[default]
    Overdamped,
    /// Second-order overdamped predictor-corrector (Heun) with the same projection.
    Overdamped2,
    /// Inertial HydroRATTLE as the paper writes it: explicit drag `-R (v - U_inf)`,
    /// mass-metric SHAKE (eq. 3) and RATTLE (eq. 4). Stable only for `dt` below about
    /// twice the momentum relaxation time.
    Rattle,
    /// Inertial with the drag implicit (backward Euler in the velocity): stable at any
    /// `dt`, and equal to [`Method::Overdamped`] as the masses go to zero.
    RattleStable,
    /// Hookean springs of stiffness [`Params::spring_stiffness`] instead of
    /// constraints, overdamped explicit Euler (the paper's costly alternative).
    Springs,
}

/// How the Brownian step produces the drift that constrained Brownian motion needs
/// (see `docs/BROWNIAN.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Drift {
    /// Fixman-type midpoint: the noise is applied through the constrained mobility
    /// `P mu` at a predictor point `x~ = x + sqrt(kT dt / 2) L xi` (`L L^T = mu`), as
    /// `sqrt(2 kT dt) P(x~) mu(x~) L^-T xi`. Its mean supplies the Ito drift
    /// `kT div(P mu)` (including any `div mu`), so the chain samples the flexible
    /// ("stiff bond") equilibrium `exp(-U/kT) delta(sigma)`: a freely jointed trimer's bond
    /// angle follows `sin(theta)`. One more mobility assembly and one linear constraint
    /// solve per step.
    #[default]
    Midpoint,
    /// Noise `sqrt(2 kT dt) L xi` on the unconstrained move, then the usual projection:
    /// no drift beyond what keeps the beads on the constraints. With a constant mobility
    /// (free draining, equal beads) this samples the rigid-constraint distribution, which
    /// carries the metric factor `sqrt(det(G G^T))`; with hydrodynamic interactions it is
    /// biased further. Kept to show the bias the midpoint removes.
    Uncorrected,
}

/// Thermal noise for [`Method::Overdamped`] and [`Method::Springs`]: displacements with
/// covariance `2 kT dt mu`, drawn through a square root of the stored mobility
/// ([`Params::noise_sqrt`]: its Cholesky factor or the Lanczos `mu^(1/2)`)
/// (and for `Overdamped` projected onto the constraints). Steps with noise go through
/// [`step`](crate::integrate::step), which draws from the state's generator
/// ([`State::noise`](crate::State::noise)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brownian<T> {
    /// Thermal energy `kT` (>= 0, same units as force x length). Zero runs the
    /// deterministic step bit for bit and draws nothing.
    pub temperature: T,
    /// Drift scheme. Default [`Drift::Midpoint`].
    pub drift: Drift,
}

impl<T: Real> Brownian<T> {
    /// Noise at `kT = temperature` with the default drift ([`Drift::Midpoint`]).
    pub fn new(temperature: T) -> Self {
        Self {
            temperature,
            drift: Drift::Midpoint,
        }
    }
}

/// How a thermal step draws `L xi` with `L L^T = mu` from the stored mobility.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NoiseSqrt {
    /// Block Cholesky factor of the packed mobility: exact, `O(N^3)` a step, `tri(N)`
    /// blocks for the factor. The small-`N` and firmware path.
    Cholesky,
    /// Krylov square root `mu^(1/2) xi` from mobility products only
    /// ([`noise::lanczos`](crate::noise::lanczos)): `O(m N^2)` a step for `m`
    /// iterations, to the relative tolerance of [`Params::lanczos`]; storage
    /// `(m_max + 1) N` vectors (and no factor with [`Drift::Uncorrected`]).
    Lanczos,
    /// [`NoiseSqrt::Lanczos`] above [`LANCZOS_CROSSOVER`] beads, Cholesky up to it.
    #[default]
    Auto,
}

/// Beads above which [`NoiseSqrt::Auto`] draws the noise by Lanczos: where the Lanczos
/// step overtakes the Cholesky one for an RPY chain (f64, midpoint), measured with
/// `cargo bench --bench kernel -- noise_sqrt`: Cholesky / Lanczos 1.21 / 1.61 ms at
/// N = 96, 2.90 / 2.07 ms at 128, so about 110 interpolated (Lanczos tolerance
/// `1e-6`); at the present default `1e-3`: 1.25 / 1.65 ms at 64, 3.66 / 3.74 ms at 96,
/// 7.67 / 3.16 ms at 128 (a loaded machine), so between 96 and 128 still.
pub const LANCZOS_CROSSOVER: usize = 112;

impl NoiseSqrt {
    /// `true` when a step of `n` beads uses the Lanczos square root.
    pub const fn lanczos(self, n: usize) -> bool {
        match self {
            Self::Cholesky => false,
            Self::Lanczos => true,
            Self::Auto => n > LANCZOS_CROSSOVER,
        }
    }
}

/// Hard-sphere excluded volume as one-sided constraints in the position solve
/// ([`Method::Overdamped`] and [`Method::Overdamped2`]).
///
/// Each pair of spheres that would overlap becomes a constraint `|r_i - r_j| = a_i + a_j`
/// solved together with the bonds through the same metric and solver; a contact whose
/// multiplier would pull the pair together is released (an active-set iteration: the
/// projection's KKT conditions). Unlike a soft repulsion it has no stiffness, so it does
/// not limit `dt`. Bonded pairs are never contacts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Contacts {
    /// Most contacts held at once. Storage counts them as extra constraints
    /// ([`Layout::for_params`](crate::Layout::for_params)); a step needing more returns
    /// [`StepError::ContactsFull`](crate::StepError::ContactsFull).
    pub capacity: usize,
    /// Active-set rounds (one constraint solve each) before the step gives up with
    /// [`StepError::NoConvergence`](crate::StepError::NoConvergence) at
    /// [`Stage::Contacts`](crate::Stage::Contacts). Default 64.
    pub max_rounds: u32,
}

impl Contacts {
    /// Room for `capacity` contacts, default rounds.
    pub const fn new(capacity: usize) -> Self {
        Self {
            capacity,
            max_rounds: 64,
        }
    }
}

/// A no-slip plane wall `z = height` below the spheres, its normal `+z` (gravity is
/// expected to point towards it). It changes the mobility (the wall's image system) and
/// is a one-sided constraint: no sphere's centre may go below `height + a_i`.
///
/// The constraint is held in the overdamped position projection with the bonds and the
/// hard-sphere contacts ([`Method::Overdamped`], [`Method::Overdamped2`]; with or without
/// [`Params::contacts`]; with thermal noise for [`Method::Overdamped`]): a sphere that
/// would end below its contact height is held there, and released when the wall would
/// have to pull it. Storage: one more constraint per sphere
/// ([`Params::constraints`]). A state with a sphere below its contact height (beyond
/// the solver's tolerance) is refused
/// ([`ParticleError::BelowWall`](crate::ParticleError::BelowWall)). The other methods
/// refuse a wall ([`StepError::Unsupported`](crate::StepError::Unsupported)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wall<T> {
    /// The plane's `z` coordinate (finite).
    pub height: T,
}

impl<T> Wall<T> {
    /// The plane `z = height`.
    pub const fn new(height: T) -> Self {
        Self { height }
    }
}

/// A slit between two no-slip plane walls, the floor `z = floor` below the spheres and
/// the ceiling `z = ceiling` above them (the kernel's `slit` feature;
/// `docs/GEOMETRY.md`, "The slit"): the mobility is the superposition of both walls'
/// image systems, and each wall is a one-sided constraint as [`Wall`] is. Refused with
/// a [`Wall`] or a box beside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slit<T> {
    /// The floor's `z` coordinate (finite).
    pub floor: T,
    /// The ceiling's `z` coordinate (finite, above the floor).
    pub ceiling: T,
}

/// Everything a step needs besides the state. Build with [`Params::new`] and adjust.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params<T: Real> {
    /// Time step (> 0).
    pub dt: T,
    /// Fluid viscosity `eta` (> 0). Default 1.
    pub viscosity: T,
    /// Fluid density, for buoyancy. Default 0.
    pub fluid_density: T,
    /// Gravitational acceleration. Default `(0, 0, -1)`.
    pub gravity: T::V3,
    /// Uniform flow `V_inf`. Default zero.
    pub flow_velocity: T::V3,
    /// Ambient vorticity: the fluid rotates rigidly, `U_inf(r) = V_inf + Omega_inf x r`.
    /// Default zero.
    pub vorticity: T::V3,
    /// Hydrodynamic model. Default [`Hydro::Rpy`].
    pub hydro: Hydro,
    /// Integrator. Default [`Method::Overdamped`].
    pub method: Method,
    /// Resolve rotation: angular velocities from the 6N grand mobility (with
    /// [`Method::RattleStable`] they are integrated with rotational inertia; otherwise
    /// reported as `Omega_inf + mu_rt F`). Default false.
    pub rotation: bool,
    /// Matrix-free mobility (the recompute path): never store `mu_tt`, evaluate each
    /// pair block where it is used (storage `O(N + B)`; at the cost of one pair
    /// evaluation per block per product, which is compute, not memory traffic, so it
    /// scales with the cores: [`crate::parallel::free_product`]). In free space the
    /// same bits as the stored path at every size and on any number of threads (the
    /// same bands); above a wall or in a periodic box the same bits as the stored path
    /// below [`BANDED_MIN`](crate::parallel::BANDED_MIN) beads, on one thread. Honoured by [`Method::Overdamped`],
    /// [`Method::Overdamped2`] (its predictor's and corrector's mobilities products, no
    /// second one stored) and [`Method::Springs`]; the inertial methods factorise the
    /// mobility and refuse it ([`StepError::BadParameter`](crate::StepError::BadParameter)). With
    /// [`Params::near`] it means the near field's iterative products (`M_SD` never
    /// formed): see there. Default false.
    pub matrix_free: bool,
    /// Constraint solver. Default [`SolverKind::Auto`], tolerance 1e-10 (f64) / 1e-5 (f32), cap 100.
    pub solver: Solver<T>,
    /// Accept overlapping (not nested) spheres. Default false.
    pub allow_overlap: bool,
    /// Spring stiffness for [`Method::Springs`]. Default 1e3.
    pub spring_stiffness: T,
    /// FENE springs for [`Method::Springs`]: the maximum extension `Q0` (> 0). A bond
    /// then pulls with `-H Q / (1 - Q^2 / Q0^2)` along itself (`H` the stiffness; the
    /// bond's length is not used: FENE's rest length is zero), and a step that would
    /// stretch one to `Q0` or beyond is refused
    /// ([`BondError::Overstretched`](crate::BondError::Overstretched)). `None` (the
    /// default): Hookean springs.
    pub fene: Option<T>,
    /// Refuse an explicit-drag ([`Method::Rattle`]) step beyond the linear stability limit
    /// of the unconstrained drag, `dt < 2 lambda_min(M^1/2 mu M^1/2)`. Bonds usually remove
    /// the stiffest modes, so the true limit is often larger; beyond it the scheme can
    /// oscillate silently (bounded but wrong) instead of blowing up. Costs about 60
    /// Cholesky solves per step. Default false.
    pub stability_guard: bool,
    /// Thermal noise: [`Method::Overdamped`] and [`Method::Springs`] (Brownian
    /// displacements of covariance `2 kT dt mu`, drift per [`Brownian::drift`]) and
    /// [`Method::RattleStable`] (Langevin: a random force of covariance `2 kT R / dt`,
    /// `R = mu^-1` its implicit drag, drawn by Cholesky whatever
    /// [`Params::noise_sqrt`] says unless it names Lanczos, which is refused; the drift
    /// setting does not apply). With [`Params::matrix_free`] (`Overdamped`, `Springs`)
    /// the noise is drawn by Lanczos from matrix-free products (storage `O(N)`).
    /// [`Method::Rattle`] and [`Method::Overdamped2`] refuse a positive temperature with
    /// [`StepError::Unsupported`](crate::StepError::Unsupported). `Overdamped2` stays
    /// refused because averaging its predictor's and corrector's velocities makes the
    /// noisy step a Stratonovich-type scheme: with a position-dependent mobility it
    /// samples a drift other than the Ito drift `kT div(P mu)` the constrained
    /// equilibrium needs, and with noise of size `sqrt(dt)` its weak order is one at
    /// best, so it would cost two mobility assemblies for no gain and a wrong drift.
    /// `Rattle`'s explicit drag is stable only for `dt < ~2 m / zeta`; `RattleStable`
    /// is its thermal counterpart. Default `None`.
    pub brownian: Option<Brownian<T>>,
    /// How the thermal noise's square root of the mobility is taken. Default
    /// [`NoiseSqrt::Auto`] (Cholesky up to [`LANCZOS_CROSSOVER`] beads, Lanczos above;
    /// Lanczos at every size with [`Params::matrix_free`], which refuses
    /// [`NoiseSqrt::Cholesky`]).
    pub noise_sqrt: NoiseSqrt,
    /// Tolerance and iteration cap of the Lanczos square root (read only when it is
    /// used). Default: estimated relative error of the noise `1e-3`, 64 iterations.
    pub lanczos: Lanczos<T>,
    /// Hard-sphere contacts as one-sided constraints ([`Contacts`];
    /// [`Method::Overdamped`] and [`Method::Overdamped2`] without thermal noise; the other
    /// methods refuse them with [`StepError::Unsupported`](crate::StepError::Unsupported)).
    /// Default `None`: spheres may overlap (see [`Params::allow_overlap`]).
    pub contacts: Option<Contacts>,
    /// A no-slip plane wall below the spheres ([`Wall`]). Default `None`: unbounded fluid.
    pub wall: Option<Wall<T>>,
    /// A slit between two walls ([`Slit`]). Default `None`.
    pub slit: Option<Slit<T>>,
    /// A rectangular periodic box ([`Periodic`]; the kernel's `periodic` feature): the
    /// mobility is the Ewald-summed RPY tensor of the box (`docs/PERIODIC.md`), and
    /// every pair geometry (bonds, contacts, springs, overlap checks) takes the
    /// minimum image. Positions are kept as given, not wrapped. Refused with a wall,
    /// with [`Params::rotation`] and with [`Hydro::Oseen`]; a bond not shorter than
    /// half the box's smallest edge is refused with its index
    /// ([`BondError::BadLength`](crate::BondError::BadLength)). Default `None`.
    pub periodic: Option<Periodic<T>>,
    /// Mixed-precision constraint products: the Krylov constraint solve's products read
    /// a compact `f32` copy of the stored mobility (24 bytes a block instead of the 48
    /// of the stored symmetric `f64` block, `linalg::Sym`; written by the assembly's
    /// pass, `noise::reduced`; each product right to about `1e-7` relative, the
    /// approximation the Lanczos noise already makes). The residual that must meet
    /// [`Solver::tolerance`] is still evaluated in `f64` on the positions, so the
    /// tolerance holds as with `f64` products; the constraint move is
    /// `dt M~ G^T lambda` with `M~` the rounded mobility (the unconstrained move stays
    /// `f64`). Half the bytes per product: the products stop being bound by memory
    /// bandwidth on many cores. Taken where [`Params::compact_copy`] says (first-order
    /// [`Method::Overdamped`], deterministic or with the thermal noise whose Lanczos
    /// products read the same copy already, whose step then reuses that copy for its
    /// projection: docs/BROWNIAN.md; an `f64` kernel, a stored mobility with
    /// symmetric blocks, in free space or in a periodic box with the Ewald sums, of at
    /// least [`REDUCED_MIN`](crate::noise::reduced::REDUCED_MIN) beads, the Krylov
    /// solver); ignored elsewhere. The same bits on any number of threads, not the
    /// bits of the `f64` products (docs/BENCHMARKS.md, "Product paths"). Default false.
    pub compact_products: bool,
    /// Solve the inertial methods' ([`Method::Rattle`], [`Method::RattleStable`]) bond
    /// tensions again from the step's displacements instead of reading them off the
    /// position solve (`displacement_tensions` in `integrate/tensions.rs`): their
    /// constraint displacement `dt^2 F / m` falls below an `f32` position's rounding
    /// once `dt` is small, and the position multipliers are then rounding noise. Costs
    /// two more constraint solves per step (and a Cholesky solve for `Rattle`); the
    /// trajectory does not depend on it, only the multipliers and
    /// [`StepReport::max_tension`](crate::StepReport::max_tension). The other methods
    /// ignore it. Default: on in `f32`, off in `f64` (where both agree to rounding).
    pub resolve_tensions: bool,
    /// The `O(N log N)` fast product, to this relative tolerance. In a periodic box:
    /// its mobility summed by PSE ([`mobility::pse`](crate::mobility::pse), kernel
    /// feature `pse`; `1e-3` to `1e-6` measured, `docs/PERIODIC.md`) instead of the
    /// exact Ewald sums. In free space (no box, no wall): the fast free-space RPY
    /// product ([`mobility::free_fast`](crate::mobility::free_fast), kernel feature
    /// `fast-free`; `docs/FREE.md`, "Steps on the fast product") instead of the pair
    /// blocks, with [`Hydro::Rpy`] (Oseen is refused; free draining, which has no pair
    /// blocks, ignores it). Either gives products only, so it needs
    /// [`Params::matrix_free`] ([`Method::Overdamped`], [`Method::Overdamped2`],
    /// [`Method::Springs`]; the noise by Lanczos from the fast products) and, with
    /// constraints, the Krylov solver ([`SolverKind::Auto`] resolves to it); the rest
    /// (rotation included, except with the iterative near field, whose far field is then
    /// the fast product's grand product) is refused with
    /// [`StepError::Unsupported`](crate::StepError::Unsupported), and so is a wall. Its
    /// storage is the caller's: in a box
    /// [`Workspace::with_pse`](crate::Workspace::with_pse), sized by
    /// [`pse_storage`](crate::integrate::pse_storage); in free space
    /// [`Workspace::with_fast`](crate::Workspace::with_fast), sized by
    /// [`fast_storage`](crate::integrate::fast_storage). Default `None`: the Ewald
    /// sums in a box, the pair blocks in free space, the same bits as before.
    pub pse: Option<f64>,
    /// Stokesian dynamics' near field ([`NearField`], kernel
    /// feature `near`): the step's mobility is the dense Stokesian dynamics grand
    /// mobility (`stokesian::mobility`), `M_SD = (M_far^-1 +
    /// R_near)^-1` with the exact two-sphere and sphere-wall lubrication of the pairs
    /// and spheres inside the cutoffs, instead of the far field alone. Torque-free
    /// spheres move with its translational blocks, `U = M_SD,tt F`; with
    /// [`Params::rotation`] they spin with `W = M_SD,rt F`. Everything that reads the
    /// stored mobility reads these blocks: the constraint solvers' metric (sweep,
    /// Newton, Krylov), the contacts' and the wall's projection, and the thermal
    /// noise's Cholesky factor with its midpoint drift. [`Hydro::Rpy`] in free space or
    /// above a wall; [`Method::Overdamped`] and [`Method::Overdamped2`]; storage
    /// `tri(2n)` blocks and `(6n)^2` scalars more, with the stored mobility in blocks
    /// of nine ([`Layout::for_params`](crate::Layout::for_params)). Refused with
    /// [`StepError::Unsupported`](crate::StepError::Unsupported): the other methods and
    /// levels, the box's PSE sums, Lanczos noise
    /// ([`NoiseSqrt::Lanczos`], or [`NoiseSqrt::Auto`] above [`LANCZOS_CROSSOVER`]).
    /// With [`Params::matrix_free`] `M_SD` is never formed: each mobility is one
    /// iterative product (`stokesian::iterative`, conjugate gradients over the close
    /// pairs to [`Solver::tolerance`](crate::Solver::tolerance), the far field's grand
    /// mobility assembled once), `O(N^2)` like a RPY step instead of `O(N^3)`;
    /// deterministic `Overdamped` and `Overdamped2` without constraints, in free space
    /// or in the box (the rest refused), room for [`NEAR_PAIRS_PER_SPHERE`] close pairs
    /// a sphere. `docs/NEAR.md`. Default `None`: the far field alone, the same bits as before.
    /// The field exists without the `near` feature too (so that a struct literal, a
    /// firmware's `const` parameters, compiles either way), with a type that has no
    /// value there: only `None`.
    pub near: Option<NearField<T>>,
}

impl<T: Real> Params<T> {
    /// Defaults as documented on each field, with time step `dt`.
    pub fn new(dt: T) -> Self {
        let tolerance = if T::EPSILON.to_f64() < 1e-10 {
            1e-10
        } else {
            1e-5
        };
        Self {
            dt,
            viscosity: T::ONE,
            fluid_density: T::ZERO,
            gravity: T::v3(T::ZERO, T::ZERO, -T::ONE),
            flow_velocity: T::V3_ZERO,
            vorticity: T::V3_ZERO,
            hydro: Hydro::Rpy,
            method: Method::Overdamped,
            rotation: false,
            matrix_free: false,
            solver: Solver {
                kind: SolverKind::Auto,
                tolerance: T::from_f64(tolerance),
                max_iterations: 100,
            },
            allow_overlap: false,
            spring_stiffness: T::from_f64(1e3),
            fene: None,
            stability_guard: false,
            brownian: None,
            noise_sqrt: NoiseSqrt::Auto,
            lanczos: Lanczos::default(),
            contacts: None,
            wall: None,
            slit: None,
            periodic: None,
            compact_products: false,
            resolve_tensions: T::EPSILON.to_f64() > 1e-10,
            pse: None,
            near: None,
        }
    }

    /// Whether the step's mobility has Stokesian dynamics' near field ([`Params::near`];
    /// always `false` without the kernel's `near` feature).
    #[inline(always)]
    pub const fn near_on(&self) -> bool {
        cfg!(feature = "near") && self.near.is_some()
    }

    /// Ambient fluid velocity at `r`: `V_inf + Omega_inf x r`.
    #[inline]
    pub fn flow_at(&self, r: T::V3) -> T::V3 {
        self.flow_velocity + T::cross(self.vorticity, r)
    }

    /// The geometry these parameters name ([`Place`](crate::geometry::Place)): the one
    /// reading of [`Params::wall`] and [`Params::periodic`] that the checks, the
    /// workspace's sizes, the noise and the pair geometry ask.
    #[inline(always)]
    pub const fn place(&self) -> crate::geometry::Place<T> {
        let wall = match self.wall {
            Some(w) => Some(w.height),
            None => None,
        };
        let slit = match self.slit {
            Some(s) => Some((s.floor, s.ceiling)),
            None => None,
        };
        crate::geometry::Place::new(crate::geometry::Named {
            wall,
            slit,
            cell: self.periodic,
            pse: self.pse.is_some(),
        })
    }

    /// `true` when a thermal step of `n` beads draws its noise by Lanczos: as
    /// [`NoiseSqrt::lanczos`] picks, and always with [`Params::matrix_free`] (there is no
    /// stored mobility to factorise; [`NoiseSqrt::Cholesky`] with `matrix_free` is
    /// refused).
    pub const fn lanczos_noise(&self, n: usize) -> bool {
        self.matrix_free || self.noise_sqrt.lanczos(n)
    }

    /// Constraint slots a step of `n` spheres with `bonds` bonds holds: the bonds, the
    /// contact capacity when contacts are on, and one wall link per sphere for each hard
    /// surface (a wall's plane; a slit's two).
    pub const fn constraints(&self, n: usize, bonds: usize) -> usize {
        let contacts = match self.contacts {
            Some(c) => c.capacity,
            None => 0,
        };
        // One link a sphere for each hard surface of the place.
        bonds + contacts + n * self.place().surfaces().len()
    }

    /// The solver that runs for `n` spheres and `bonds` bonds: [`SolverKind::Auto`]
    /// resolved once, from every constraint row the step may solve
    /// ([`Params::constraints`]: bonds, contact capacity, wall links), not from the rows
    /// held in one round; with contacts by
    /// [`SolverKind::resolve_contacts`](crate::SolverKind::resolve_contacts) (Newton on
    /// piles up to a measured size). [`Layout::for_params`](crate::Layout::for_params) sizes the
    /// storage from this same choice, and every stage of the step runs it, so the two
    /// cannot disagree.
    /// With a fast product ([`Params::pse`]: PSE in a box, the fast free-space product
    /// without a wall) `Auto` is Krylov at every size: the only solver that needs
    /// products alone. So with the iterative near field ([`Params::near`] with
    /// [`Params::matrix_free`]), whose constraint metric is a product of `M_SD`.
    pub const fn solver_kind(&self, n: usize, bonds: usize) -> SolverKind {
        match (self.solver.kind, self.pse, self.periodic) {
            (SolverKind::Auto, Some(_), Some(_)) => SolverKind::Krylov,
            (SolverKind::Auto, Some(_), None) if self.wall.is_none() => SolverKind::Krylov,
            // The iterative near field's metric has products only (`integrate/near_iter`).
            (SolverKind::Auto, ..) if self.near_on() && self.matrix_free => SolverKind::Krylov,
            (kind, ..) if self.contacts.is_some() => {
                kind.resolve_contacts(self.constraints(n, bonds), n)
            }
            (kind, ..) => kind.resolve(self.constraints(n, bonds)),
        }
    }

    /// Whether a step of `n` beads and `bonds` bonds keeps the compact `f32` copy of
    /// the mobility for its constraint products ([`Params::compact_products`]): asked
    /// for, first-order [`Method::Overdamped`] without noise or with the noise that
    /// reads the reduced copy already (`noise::reduced::for_noise`: the midpoint drift,
    /// Lanczos noise, no Ewald sums; its copy is reused, not made twice), a stored mobility of
    /// symmetric blocks (free space, or a periodic box summed by Ewald; not above a
    /// wall, whose blocks are not symmetric, nor with [`Params::pse`] in a box, which
    /// stores nothing), an `f64` kernel, at least
    /// [`REDUCED_MIN`](crate::noise::reduced::REDUCED_MIN) beads, the Krylov solver.
    pub const fn compact_copy(&self, n: usize, bonds: usize) -> bool {
        self.compact_products
            && matches!(self.method, Method::Overdamped)
            && (self.brownian.is_none() || crate::noise::reduced::for_noise(self, n))
            && !self.matrix_free
            && self.place().stores_symmetric()
            && !self.near_on()
            && core::mem::size_of::<T>() == 8
            && n >= crate::noise::reduced::REDUCED_MIN
            && matches!(self.solver_kind(n, bonds), SolverKind::Krylov)
    }
}
