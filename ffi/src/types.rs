//! The `repr(C)` types of the interface and their conversions to the kernel's.
//!
//! Enumerations cross the boundary as `u32` fields (a C caller can store any value in
//! an enum, and an out-of-range value in a Rust enum would be undefined behaviour);
//! the named values are the `Hr*` enums below, exported to the header.

use kernel::{Brownian, Drift, Hydro, Method, Params, Real, SolverKind};

/// Status of a call: 0 for success, negative for a misuse of the interface caught
/// before the kernel ran, positive for the kernel's `StepError` variants (same order).
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrStatus {
    /// Success.
    Ok = 0,
    /// A required pointer is null.
    NullPointer = -1,
    /// A count is out of range (`hr_max_particles`, `hr_max_bonds`) or a size overflows.
    Size = -2,
    /// An enumeration field holds a value with no meaning.
    Enum = -3,
    /// A pointer is not aligned for its element type.
    Alignment = -4,
    /// Two arrays overlap where one of them is written.
    Aliasing = -5,
    /// `StepError::BadTimeStep`.
    BadTimeStep = 1,
    /// `StepError::BadParameter`.
    BadParameter = 2,
    /// `StepError::Particle`.
    Particle = 3,
    /// `StepError::Bond`.
    Bond = 4,
    /// `StepError::Linalg`.
    Linalg = 5,
    /// `StepError::NoConvergence`.
    NoConvergence = 6,
    /// `StepError::Degenerate`.
    Degenerate = 7,
    /// `StepError::NonFinite`.
    NonFinite = 8,
    /// `StepError::Overlap`.
    Overlap = 9,
    /// `StepError::Storage`: the storage buffer is smaller than `hr_storage_bytes_*`.
    Storage = 10,
    /// `StepError::StateLength`.
    StateLength = 11,
    /// `StepError::Unstable`.
    Unstable = 12,
    /// `StepError::Unsupported`: the combination of parameters is not implemented.
    Unsupported = 13,
    /// `StepError::ContactsFull`: more contacts at once than the capacity
    /// (`error_index`). The C interface sets no contacts, so this is never returned
    /// today; the value is reserved so that codes stay stable.
    ContactsFull = 14,
    /// `StepError::Infeasible`: constraints that cannot all hold (`error_index`,
    /// `error_other`: the first two of the dependent set). Reserved like
    /// `ContactsFull`: without contacts a dependent set is rarely infeasible.
    Infeasible = 15,
}

/// Values of [`HrParams::method`] (the kernel's `Method`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrMethod {
    /// HydroSHAKE, first order.
    Overdamped = 0,
    /// Heun predictor-corrector, second order.
    Overdamped2 = 1,
    /// The paper's velocity-Verlet HydroRATTLE with explicit drag.
    Rattle = 2,
    /// Inertial with implicit drag (stable at any time step).
    RattleStable = 3,
    /// Hookean springs instead of constraints.
    Springs = 4,
}

/// Values of [`HrParams::hydro`] (the kernel's `Hydro`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrHydro {
    /// Rotne-Prager-Yamakawa.
    Rpy = 0,
    /// Oseen.
    Oseen = 1,
    /// Self terms only.
    FreeDraining = 2,
}

/// Values of [`HrParams::solver`] (the kernel's `SolverKind`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrSolver {
    /// Newton up to 32 bonds, Krylov above.
    Auto = 0,
    /// Cyclic SHAKE/RATTLE sweeps.
    Sweep = 1,
    /// Dense Newton.
    Newton = 2,
    /// Chord Newton with preconditioned conjugate gradients.
    Krylov = 3,
}

/// Values of [`HrParams::drift`] (the kernel's `Drift`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HrDrift {
    /// Fixman-type midpoint: the stiff-bond (flexible chain) equilibrium.
    Midpoint = 0,
    /// Noise then projection, no correction (the rigid-constraint bias).
    Uncorrected = 1,
}

/// A thermal-noise generator (the kernel's `Noise`) as plain data: its whole state is
/// these six words, so saving it is copying the struct and restoring it is copying it
/// back (`hr_noise_seed` makes one). A step at temperature draws from it and writes it
/// back only when it succeeds; words no generator has are refused with
/// [`HrStatus::BadParameter`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HrNoise {
    /// xoshiro256++ state, then the pending Box-Muller spare (flag, bits).
    pub words: [u64; 6],
}

/// Step parameters (the kernel's `Params`); start from `hr_params_default_*`.
/// Flags are bytes: 0 is false, anything else true.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HrParams<T> {
    /// Time step (> 0).
    pub dt: T,
    /// Fluid viscosity (> 0).
    pub viscosity: T,
    /// Fluid density, for buoyancy.
    pub fluid_density: T,
    /// Gravitational acceleration.
    pub gravity: [T; 3],
    /// Uniform flow velocity.
    pub flow_velocity: [T; 3],
    /// Ambient vorticity.
    pub vorticity: [T; 3],
    /// An [`HrHydro`] value.
    pub hydro: u32,
    /// An [`HrMethod`] value.
    pub method: u32,
    /// An [`HrSolver`] value.
    pub solver: u32,
    /// Constraint tolerance (relative bond-length error).
    pub tolerance: T,
    /// Constraint iteration cap (> 0).
    pub max_iterations: u32,
    /// Spring stiffness for [`HrMethod::Springs`].
    pub spring_stiffness: T,
    /// Resolve rotation.
    pub rotation: u8,
    /// Never store the mobility (Overdamped and Springs).
    pub matrix_free: u8,
    /// Accept overlapping (not nested) spheres.
    pub allow_overlap: u8,
    /// Refuse explicit-drag steps beyond the stability limit.
    pub stability_guard: u8,
    /// Thermal energy kT (>= 0; 0: deterministic). A step at kT > 0 needs the state's
    /// generator ([`HrState::noise`]) and `method` Overdamped.
    pub temperature: T,
    /// An [`HrDrift`] value (used when `temperature > 0`).
    pub drift: u32,
    /// Step with Stokesian dynamics' near field (the kernel's `Params::near`,
    /// `docs/NEAR.md`): RPY with the exact two-sphere and sphere-wall lubrication of the
    /// pairs and spheres within the cutoffs below. Overdamped and Overdamped2, dense.
    pub near_field: u8,
    /// Pairs whose surface gap is below this many mean radii are corrected (default 4).
    pub near_cutoff: T,
    /// Spheres nearer the wall than this many radii are corrected (default 4).
    pub near_wall_cutoff: T,
    /// The smallest gap the near field sees, in radii (> 0; default 1e-3).
    pub near_min_gap: T,
}

/// `f32` parameters.
pub type HrParamsF32 = HrParams<f32>;
/// `f64` parameters.
pub type HrParamsF64 = HrParams<f64>;

/// One bond: particles `i` and `j` held at `length`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HrBond<T> {
    /// First particle.
    pub i: u32,
    /// Second particle.
    pub j: u32,
    /// Centre-to-centre length.
    pub length: T,
}

/// `f32` bond.
pub type HrBondF32 = HrBond<f32>;
/// `f64` bond.
pub type HrBondF64 = HrBond<f64>;

/// The caller's particles: `n` entries in each array, positions, velocities and
/// angular velocities as `[x, y, z]` triples. `time` advances by `dt` on success.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct HrState<T> {
    /// Number of particles.
    pub n: usize,
    /// Centres (written).
    pub pos: *mut [T; 3],
    /// Velocities (written).
    pub vel: *mut [T; 3],
    /// Angular velocities (written).
    pub omega: *mut [T; 3],
    /// Radii (read).
    pub radius: *const T,
    /// Densities (read).
    pub density: *const T,
    /// Simulation time (written).
    pub time: T,
    /// The thermal-noise generator (read, and written when a step at temperature
    /// succeeds); null for a deterministic run.
    pub noise: *mut HrNoise,
}

/// `f32` state.
pub type HrStateF32 = HrState<f32>;
/// `f64` state.
pub type HrStateF64 = HrState<f64>;

/// What a step measured (the kernel's `StepReport`) and, when it failed, where.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HrReport<T> {
    /// Position-constraint iterations of the final solve.
    pub iterations: u32,
    /// Velocity-constraint iterations (0 where there is none).
    pub velocity_iterations: u32,
    /// Largest relative bond-length error after the step.
    pub residual: T,
    /// Largest bond tension.
    pub max_tension: T,
    /// On failure: the particle, bond or matrix row at fault (the first of two), or
    /// the bytes of storage needed for [`HrStatus::Storage`].
    pub error_index: u64,
    /// On failure: the second particle of a pair, the iterations done, or the bytes
    /// of storage given.
    pub error_other: u64,
    /// On failure: the stage (1 mobility, 2 drag, 3 positions, 4 velocities,
    /// 5 stability, 6 contacts), 0 where none applies.
    pub error_stage: u32,
    /// On failure: the residual left, or the time step refused as unstable.
    pub error_value: f64,
    /// On failure: the stability limit.
    pub error_limit: f64,
}

/// `f32` report.
pub type HrReportF32 = HrReport<f32>;
/// `f64` report.
pub type HrReportF64 = HrReport<f64>;

impl<T: Real> HrParams<T> {
    /// The kernel's defaults.
    pub fn from_kernel(p: &Params<T>) -> Self {
        let v = |v: T::V3| T::xyz(v);
        let near = p.near.unwrap_or_default();
        Self {
            dt: p.dt,
            viscosity: p.viscosity,
            fluid_density: p.fluid_density,
            gravity: v(p.gravity),
            flow_velocity: v(p.flow_velocity),
            vorticity: v(p.vorticity),
            hydro: match p.hydro {
                Hydro::Rpy => HrHydro::Rpy,
                Hydro::Oseen => HrHydro::Oseen,
                Hydro::FreeDraining => HrHydro::FreeDraining,
            } as u32,
            method: match p.method {
                Method::Overdamped => HrMethod::Overdamped,
                Method::Overdamped2 => HrMethod::Overdamped2,
                Method::Rattle => HrMethod::Rattle,
                Method::RattleStable => HrMethod::RattleStable,
                Method::Springs => HrMethod::Springs,
            } as u32,
            solver: match p.solver.kind {
                SolverKind::Auto => HrSolver::Auto,
                SolverKind::Sweep => HrSolver::Sweep,
                SolverKind::Newton => HrSolver::Newton,
                SolverKind::Krylov => HrSolver::Krylov,
            } as u32,
            tolerance: p.solver.tolerance,
            max_iterations: p.solver.max_iterations,
            spring_stiffness: p.spring_stiffness,
            rotation: p.rotation.into(),
            matrix_free: p.matrix_free.into(),
            allow_overlap: p.allow_overlap.into(),
            stability_guard: p.stability_guard.into(),
            temperature: p.brownian.map_or(T::ZERO, |b| b.temperature),
            drift: match p.brownian.map_or(Drift::Midpoint, |b| b.drift) {
                Drift::Midpoint => HrDrift::Midpoint,
                Drift::Uncorrected => HrDrift::Uncorrected,
            } as u32,
            near_field: p.near.is_some().into(),
            near_cutoff: near.cutoff,
            near_wall_cutoff: near.wall_cutoff,
            near_min_gap: near.min_gap,
        }
    }

    /// The kernel's parameters, or [`HrStatus::Enum`] for an unknown enum value.
    pub fn to_kernel(&self) -> Result<Params<T>, HrStatus> {
        let mut p = Params::new(self.dt);
        p.viscosity = self.viscosity;
        p.fluid_density = self.fluid_density;
        let [gx, gy, gz] = self.gravity;
        p.gravity = T::v3(gx, gy, gz);
        let [ux, uy, uz] = self.flow_velocity;
        p.flow_velocity = T::v3(ux, uy, uz);
        let [wx, wy, wz] = self.vorticity;
        p.vorticity = T::v3(wx, wy, wz);
        p.hydro = match self.hydro {
            0 => Hydro::Rpy,
            1 => Hydro::Oseen,
            2 => Hydro::FreeDraining,
            _ => return Err(HrStatus::Enum),
        };
        p.method = match self.method {
            0 => Method::Overdamped,
            1 => Method::Overdamped2,
            2 => Method::Rattle,
            3 => Method::RattleStable,
            4 => Method::Springs,
            _ => return Err(HrStatus::Enum),
        };
        p.solver.kind = match self.solver {
            0 => SolverKind::Auto,
            1 => SolverKind::Sweep,
            2 => SolverKind::Newton,
            3 => SolverKind::Krylov,
            _ => return Err(HrStatus::Enum),
        };
        p.solver.tolerance = self.tolerance;
        p.solver.max_iterations = self.max_iterations;
        p.spring_stiffness = self.spring_stiffness;
        p.rotation = self.rotation != 0;
        p.matrix_free = self.matrix_free != 0;
        p.allow_overlap = self.allow_overlap != 0;
        p.stability_guard = self.stability_guard != 0;
        let drift = match self.drift {
            0 => Drift::Midpoint,
            1 => Drift::Uncorrected,
            _ => return Err(HrStatus::Enum),
        };
        p.near = (self.near_field != 0).then_some(kernel::stokesian::NearField {
            cutoff: self.near_cutoff,
            wall_cutoff: self.near_wall_cutoff,
            min_gap: self.near_min_gap,
        });
        // kT = 0 is the deterministic step (and its storage); anything else, even a
        // bad value, goes to the kernel, which refuses what is invalid.
        if self.temperature != T::ZERO {
            p.brownian = Some(Brownian {
                temperature: self.temperature,
                drift,
            });
        }
        Ok(p)
    }
}
