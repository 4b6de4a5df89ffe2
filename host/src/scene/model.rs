//! The resolved scene's parts: fluid, particles, bonds, model and integrator settings.

use serde::{Deserialize, Serialize};

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

/// Hydrodynamic interaction model: the kernel's [`hydrorattle::Hydro`], by its names.
pub use hydrorattle::Hydro as Hydrodynamics;

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
    #[serde(serialize_with = "super::names::serialize")]
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

/// Time integration method (`docs/MODEL.md#integrators`): the kernel's
/// [`hydrorattle::Method`], by its names.
pub use hydrorattle::Method;

/// Constraint solver: the kernel's [`hydrorattle::SolverKind`], by its names.
pub use hydrorattle::SolverKind as Solver;

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
    #[serde(serialize_with = "super::names::serialize")]
    pub method: Method,
    /// Time step (> 0).
    pub dt: f64,
    /// Simulated time (> 0, at least one step).
    pub duration: f64,
    /// Constraint solver.
    #[serde(serialize_with = "super::names::serialize")]
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
