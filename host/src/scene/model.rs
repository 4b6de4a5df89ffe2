//! The resolved scene's parts: fluid, particles, bonds, model and integrator settings.

use serde::{Deserialize, Serialize};

use super::names::{Kernel, by_kernel_name};

/// The fluid around the particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Fluid {
    /// Dynamic viscosity `eta` (> 0).
    pub viscosity: f64,
    /// Fluid density (>= 0); enters only the buoyant weight.
    pub density: f64,
}

/// The ambient flow `U_inf(r) = velocity + vorticity x r`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Flow {
    /// Uniform flow velocity.
    pub velocity: [f64; 3],
    /// Angular velocity of the ambient rigid rotation.
    pub vorticity: [f64; 3],
}

/// One rigid sphere.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Particle {
    /// Centre.
    pub position: [f64; 3],
    /// Radius (> 0).
    pub radius: f64,
    /// Material density (>= 0; > 0 for the inertial methods).
    pub density: f64,
    /// Initial velocity (the inertial methods start from it; the overdamped ones
    /// compute velocities from the forces).
    pub velocity: [f64; 3],
    /// Initial angular velocity (used with `rotation = true` and inertia).
    pub angular_velocity: [f64; 3],
}

/// A rigid bond (holonomic distance constraint) between two particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bond {
    /// First particle (0-based index).
    pub i: usize,
    /// Second particle (0-based index), different from `i`.
    pub j: usize,
    /// Centre-to-centre distance the bond holds.
    pub length: f64,
}

/// Hydrodynamic interaction model (named by the kernel's [`hydrorattle::Hydro`] names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Hydrodynamics {
    /// Rotne-Prager-Yamakawa grand mobility (with its overlap regularisation).
    #[default]
    Rpy,
    /// Oseen tensor (not positive definite when beads come close).
    Oseen,
    /// Self terms only: no hydrodynamic interaction between beads.
    FreeDraining,
}

impl Hydrodynamics {
    /// The kernel's model.
    pub fn kernel(self) -> hydrorattle::Hydro {
        match self {
            Self::Rpy => hydrorattle::Hydro::Rpy,
            Self::Oseen => hydrorattle::Hydro::Oseen,
            Self::FreeDraining => hydrorattle::Hydro::FreeDraining,
        }
    }
}

impl Kernel for Hydrodynamics {
    type K = hydrorattle::Hydro;
    const ALL: &'static [Self] = &[Self::Rpy, Self::Oseen, Self::FreeDraining];
    fn kernel(self) -> hydrorattle::Hydro {
        Hydrodynamics::kernel(self)
    }
}
by_kernel_name!(Hydrodynamics);

/// Whether the driver may pick the model level itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// The driver may choose the cheapest model adequate for the scene.
    Auto,
    /// Use exactly the model written in the scene.
    #[default]
    Manual,
}

/// What to do with spheres that overlap (without nesting) at t = 0. Overlap at the
/// start is almost always a typing error, so it is refused unless the scene asks for
/// it; during the run spheres may come to overlap (the paper's chains have no excluded
/// volume; `[contact]` adds hard or soft excluded volume).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Overlap {
    /// Refuse the scene.
    #[default]
    Reject,
    /// Accept it.
    Allow,
}

/// The physical model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub struct Model {
    /// Hydrodynamic interactions.
    pub hydrodynamics: Hydrodynamics,
    /// Whether particle inertia is resolved.
    pub inertia: bool,
    /// Whether rotations (angular velocities, torques) are resolved.
    pub rotation: bool,
    /// Model-level selection.
    pub level: Level,
    /// Overlap policy.
    pub overlap: Overlap,
}

/// Time integration method (`docs/MODEL.md#integrators`), named by the kernel's
/// [`hydrorattle::Method`] names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// First-order overdamped step with constraint projection (HydroSHAKE).
    Overdamped,
    /// Second-order (predictor-corrector) overdamped step.
    Overdamped2,
    /// The paper's inertial HydroRATTLE, explicit drag.
    Rattle,
    /// Inertial RATTLE with a drag treatment stable at any `dt`.
    RattleStable,
    /// Hookean springs instead of constraints.
    Springs,
}

impl Kernel for Method {
    type K = hydrorattle::Method;
    const ALL: &'static [Self] = &Method::ALL;
    fn kernel(self) -> hydrorattle::Method {
        Method::kernel(self)
    }
}
by_kernel_name!(Method);

impl Method {
    /// Every method, in declaration order.
    pub const ALL: [Method; 5] = [
        Method::Overdamped,
        Method::Overdamped2,
        Method::Rattle,
        Method::RattleStable,
        Method::Springs,
    ];

    /// Whether the method carries particle momenta (and so needs positive masses).
    pub fn is_inertial(self) -> bool {
        matches!(self, Method::Rattle | Method::RattleStable)
    }

    /// The kernel's method.
    pub fn kernel(self) -> hydrorattle::Method {
        match self {
            Method::Overdamped => hydrorattle::Method::Overdamped,
            Method::Overdamped2 => hydrorattle::Method::Overdamped2,
            Method::Rattle => hydrorattle::Method::Rattle,
            Method::RattleStable => hydrorattle::Method::RattleStable,
            Method::Springs => hydrorattle::Method::Springs,
        }
    }
}

/// Constraint solver (named by the kernel's [`hydrorattle::SolverKind`] names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// The kernel's choice: Newton up to [`hydrorattle::DENSE_BONDS_MAX`] bonds, Krylov
    /// above (the same bits as Newton for the small scenes).
    #[default]
    Auto,
    /// Cyclic SHAKE sweeps, one constraint at a time.
    Sweep,
    /// Newton iteration on the whole (dense) constraint Jacobian: `O(B^2)` storage,
    /// `O(B^3)` per iteration.
    Newton,
    /// Chord Newton with preconditioned conjugate gradients: `O(B)` storage, one
    /// mobility product per iteration (thousands of beads).
    Krylov,
}

impl Kernel for Solver {
    type K = hydrorattle::SolverKind;
    const ALL: &'static [Self] = &[Self::Auto, Self::Sweep, Self::Newton, Self::Krylov];
    fn kernel(self) -> hydrorattle::SolverKind {
        self.kind()
    }
}
by_kernel_name!(Solver);

impl Solver {
    /// The kernel's solver kind.
    pub fn kind(self) -> hydrorattle::SolverKind {
        match self {
            Solver::Auto => hydrorattle::SolverKind::Auto,
            Solver::Sweep => hydrorattle::SolverKind::Sweep,
            Solver::Newton => hydrorattle::SolverKind::Newton,
            Solver::Krylov => hydrorattle::SolverKind::Krylov,
        }
    }
}

/// Floating-point precision of the kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Single precision.
    F32,
    /// Double precision.
    #[default]
    F64,
}

/// How to integrate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Integrator {
    /// Method.
    pub method: Method,
    /// Time step (> 0).
    pub dt: f64,
    /// Simulated time (> 0, at least one step).
    pub duration: f64,
    /// Constraint solver.
    pub solver: Solver,
    /// Constraint tolerance (> 0).
    pub tolerance: f64,
    /// Iteration cap of the constraint solver (>= 1).
    pub max_iterations: usize,
    /// Kernel precision.
    pub precision: Precision,
    /// Spring constant for `method = "springs"` (> 0).
    pub stiffness: f64,
    /// FENE springs for `method = "springs"`: their maximum extension `Q0` (> 0; the
    /// kernel's [`hydrorattle::Params::fene`]). `None`: Hookean springs.
    pub fene: Option<f64>,
    /// Never store the mobility (the kernel's `Params::matrix_free`: storage `O(N)`,
    /// pair blocks evaluated where they are used; thermal noise by Lanczos).
    /// `method = "overdamped"` or `"springs"` with `level = "manual"` only.
    pub matrix_free: bool,
    /// Mixed-precision constraint products (the kernel's `Params::compact_products`:
    /// the Krylov solve's products read an `f32` copy of the stored mobility, the
    /// residual stays `f64`; half the bytes per product). The kernel takes it where it
    /// applies (deterministic overdamped, `f64`, free space or an Ewald box, at least
    /// 700 beads, Krylov) and ignores it elsewhere (a wall, PSE, noise).
    pub compact_products: bool,
}

impl Integrator {
    /// Number of steps: `duration / dt` rounded to the nearest integer (at least 1).
    pub fn steps(&self) -> usize {
        steps_of(self.duration, self.dt)
    }
}

fn steps_of(duration: f64, dt: f64) -> usize {
    ((duration / dt).round() as usize).max(1)
}

/// Trajectory output settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Output {
    /// Steps between trajectory frames (>= 1).
    pub every: usize,
}
