//! Several systems stepped side by side in the lanes of one value, each keeping the
//! bits of its own `f64` step (issue 31: the small step at half the core's vector
//! peak).
//!
//! One 25-bead step is a chain of small dependent pieces (a 24 x 24 Cholesky, its
//! solves, 300 pair blocks) that wider vectors barely speed up
//! (`docs/BENCHMARKS.md`, "The peak, measured beside the step"). `K` independent
//! systems of the same shape, though, do the same operations in the same order: the
//! kernel, written once against [`Real`], runs unchanged on [`Lanes<K>`] (`K` `f64`
//! values, system `k` in lane `k`), and every `+ - * /` and root becomes one packed
//! instruction for all `K` systems.
//!
//! **Measured, it does not pay** (docs/BENCHMARKS.md, "Several systems in the
//! lanes"): the `f64` step's heavy loops are already vector loops across beads and
//! pairs, so the lanes add moves, not width (9.0 us a system-step at `K = 4` in the
//! AVX2 build against 8.0 us for one `f64` step, with no divergence at all), and
//! lanes that converge in different Newton iteration counts fall back. It is kept as
//! a bit-exact way to step lockstep systems together.
//!
//! **Same bits.** Every arithmetic operation of [`Lanes`] is the `f64` operation lane
//! by lane, and its vectors and matrices repeat glam's order of operations
//! ([`LV3`], [`LM3`]). So as long as every decision the step takes (a comparison, a
//! finiteness check, a value taken out as one `f64`) comes out the same on all lanes,
//! lane `k` computes exactly what system `k`'s own `f64` step computes. Where the
//! lanes disagree, the decision follows lane 0 and the lanes that answered otherwise
//! are marked ([`diverged`]); [`Batch::step`] keeps the unmarked lanes (at every
//! decision they took their own side, so their values are their own steps') and steps
//! each marked system by itself in `f64`. A lane step that fails is redone system by
//! system, so that each system gets its own result or its own error, with its state
//! as it was.
//!
//! Two choices that differ between lanes without changing any lane's bits are made
//! per lane instead of raising a divergence (kernel hooks of [`Real`]): the RPY
//! block's far or overlapping branch (both evaluated, each lane taking its own), and
//! the search for the bond of largest error (run once per lane). What still diverges
//! is what changes a lane's path: mostly one system converging in fewer Newton
//! iterations than another (docs/BENCHMARKS.md, "Several systems in the lanes").
//!
//! ```
//! use hydrorattle::{Bond, Layout, NoForce, Params, Particle, ParticleSet};
//! use hydrorattle_heap::Buffers;
//! use hydrorattle_parallel::batch::{Batch, Lanes};
//!
//! // Four dimers, each at its own height.
//! let mut sets: [ParticleSet<f64, 2>; 4] = core::array::from_fn(|k| {
//!     let mut s = ParticleSet::new();
//!     let z = k as f64;
//!     s.push(Particle::new(glam::DVec3::new(0.0, 0.0, z), 1.0, 2.0)).unwrap();
//!     s.push(Particle::new(glam::DVec3::new(3.0, 0.0, z), 1.0, 2.0)).unwrap();
//!     s
//! });
//! let bonds = [Bond { i: 0, j: 1, length: 3.0 }];
//! let params = Params::new(0.01);
//! let mut batch = Batch::<4>::uniform(2, &bonds, &params).unwrap();
//! let layout = Layout::for_params(&params, 2, 1);
//! let mut lanes = Buffers::<Lanes<4>>::new(layout);
//! let mut one = Buffers::<f64>::new(layout);
//! let reports = batch
//!     .step(
//!         sets.each_mut().map(|s| s.state()),
//!         &mut lanes.workspace(),
//!         &mut one.workspace(),
//!         &mut NoForce,
//!     )
//!     .unwrap();
//! assert!(reports.iter().all(|r| r.is_ok()));
//! assert_eq!(batch.counts().lane_steps, 1);
//! # use hydrorattle::glam;
//! ```

#![forbid(unsafe_code)]

mod lanes;
mod real;
mod vec;

use core::fmt;

use hydrorattle::forces::NoForce;
use hydrorattle::{Bond, Params, Real, State, StepError, StepReport, Workspace};

pub use lanes::{Lanes, MAX_LANES, clear_divergence, diverged};
pub use vec::{LM3, LV3};

/// `f64` vectors, as the kernel's `f64` steps use them.
type V3 = <f64 as Real>::V3;

/// Why a batch cannot be built or stepped: the systems do not have the same shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchError {
    /// System `system` has `len` spheres, not the batch's `expected`.
    Length {
        /// The system.
        system: usize,
        /// Its spheres.
        len: usize,
        /// The batch's.
        expected: usize,
    },
    /// System `system`'s bonds join other spheres than system 0's (or are more or
    /// fewer): the lanes would need different loops.
    Bonds {
        /// The system.
        system: usize,
    },
    /// System `system`'s parameters differ from system 0's in something other than a
    /// real number (method, solver, flags, counts, an option present in one only).
    Params {
        /// The system.
        system: usize,
    },
    /// The parameters ask for what the lanes cannot share (named).
    Unsupported(&'static str),
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length {
                system,
                len,
                expected,
            } => write!(f, "system {system} has {len} spheres, the batch {expected}"),
            Self::Bonds { system } => write!(
                f,
                "system {system}'s bonds join other spheres than system 0's"
            ),
            Self::Params { system } => write!(
                f,
                "system {system}'s parameters differ from system 0's beyond their real values"
            ),
            Self::Unsupported(what) => write!(f, "not in a batch: {what}"),
        }
    }
}

impl std::error::Error for BatchError {}

/// The forces a batch adds on top of gravity: for all lanes at once and for one
/// system alone (a fallback step). Both must add, on system `k`, the same `f64`
/// operations in the same order, or the two paths give different bits.
pub trait Forces<const K: usize> {
    /// Adds forces to every lane (see [`hydrorattle::ExternalForce::add`]).
    fn lanes(&mut self, pos: &[LV3<K>], radius: &[Lanes<K>], force: &mut [LV3<K>]);
    /// Adds system `k`'s forces.
    fn system(&mut self, k: usize, pos: &[V3], radius: &[f64], force: &mut [V3]);
}

impl<const K: usize> Forces<K> for NoForce {
    fn lanes(&mut self, _: &[LV3<K>], _: &[Lanes<K>], _: &mut [LV3<K>]) {}
    fn system(&mut self, _: usize, _: &[V3], _: &[f64], _: &mut [V3]) {}
}

/// What a batch did so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Steps of the batch (each one step in the lanes).
    pub lane_steps: u64,
    /// Lane steps in which some lane's decision differed from lane 0's.
    pub diverged: u64,
    /// Lane steps that failed (every system then stepped alone).
    pub failed: u64,
    /// Systems stepped alone in `f64` after a lane step (the marked lanes of a
    /// diverged step, all `K` of a failed one).
    pub fallback_steps: u64,
}

impl Counts {
    /// The share of system steps that ran alone: `fallback_steps / (K lane_steps)`.
    pub fn fallback_rate(&self, k: usize) -> f64 {
        match self.lane_steps * k as u64 {
            0 => 0.0,
            all => self.fallback_steps as f64 / all as f64,
        }
    }
}

/// `K` systems of `n` spheres with the same bonds' topology and the same control
/// parameters, stepped together ([`Batch::step`]). Holds the lanes' copy of the
/// bonds and parameters and the packed state a step runs on (allocated once, by
/// [`Batch::new`]); the workspaces are the caller's.
#[derive(Clone, Debug)]
pub struct Batch<const K: usize> {
    n: usize,
    bonds: Vec<Bond<Lanes<K>>>,
    params: Params<Lanes<K>>,
    one_bonds: Vec<Vec<Bond<f64>>>,
    one_params: Vec<Params<f64>>,
    pos: Vec<LV3<K>>,
    vel: Vec<LV3<K>>,
    omega: Vec<LV3<K>>,
    radius: Vec<Lanes<K>>,
    density: Vec<Lanes<K>>,
    counts: Counts,
}

impl<const K: usize> Batch<K> {
    /// `K` systems of `n` spheres sharing one bond list and one set of parameters.
    ///
    /// # Errors
    /// As [`Batch::new`].
    pub fn uniform(
        n: usize,
        bonds: &[Bond<f64>],
        params: &Params<f64>,
    ) -> Result<Self, BatchError> {
        Self::new(n, [bonds; K], [params; K])
    }

    /// `K` systems of `n` spheres, system `k` with its own bonds and parameters: the
    /// bonds must join the same spheres in the same order (their lengths may differ)
    /// and the parameters may differ only in their real values ([`Params::map`]'s
    /// fields: time step, viscosity, gravity, tolerance, ...).
    ///
    /// # Errors
    /// [`BatchError::Bonds`] or [`BatchError::Params`] naming the first system that
    /// differs from system 0; [`BatchError::Unsupported`] for thermal noise (each
    /// system draws from its own generator, which the lanes cannot share) and for
    /// `K = 0`.
    pub fn new(
        n: usize,
        bonds: [&[Bond<f64>]; K],
        params: [&Params<f64>; K],
    ) -> Result<Self, BatchError> {
        if K == 0 || K > MAX_LANES {
            return Err(BatchError::Unsupported("no lanes, or more than 64"));
        }
        let topology = |b: &[Bond<f64>]| b.iter().map(|b| (b.i, b.j)).collect::<Vec<_>>();
        if let Some(system) = (1..K).find(|&k| topology(bonds[k]) != topology(bonds[0])) {
            return Err(BatchError::Bonds { system });
        }
        // The control parameters: every real field set to one, the rest compared.
        let shape = |p: &Params<f64>| p.map(|_| 1.0);
        if let Some(system) = (1..K).find(|&k| shape(params[k]) != shape(params[0])) {
            return Err(BatchError::Params { system });
        }
        if params
            .iter()
            .any(|p| p.brownian.is_some_and(|b| b.temperature != 0.0))
        {
            return Err(BatchError::Unsupported(
                "thermal noise (each system draws from its own generator)",
            ));
        }
        let bonds_lanes = (0..bonds[0].len())
            .map(|l| Bond {
                i: bonds[0][l].i,
                j: bonds[0][l].j,
                length: Lanes(core::array::from_fn(|k| bonds[k][l].length)),
            })
            .collect();
        Ok(Self {
            n,
            bonds: bonds_lanes,
            params: zip_params(params)?,
            one_bonds: bonds.iter().map(|b| b.to_vec()).collect(),
            one_params: params.iter().map(|&&p| p).collect(),
            pos: vec![LV3::default(); n],
            vel: vec![LV3::default(); n],
            omega: vec![LV3::default(); n],
            radius: vec![Lanes::default(); n],
            density: vec![Lanes::default(); n],
            counts: Counts::default(),
        })
    }

    /// Spheres a system has.
    pub fn len(&self) -> usize {
        self.n
    }

    /// `true` for systems of no spheres.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// What the batch did so far.
    pub fn counts(&self) -> Counts {
        self.counts
    }

    /// The lanes' parameters (system `k`'s values in lane `k`).
    pub fn params(&self) -> &Params<Lanes<K>> {
        &self.params
    }

    /// One step of every system: once in the lanes, and for each system whose lane
    /// diverged (or all, where the lane step failed) again by itself in `f64` (with
    /// `one`). System
    /// `k`'s result is what [`hydrorattle::step_slices`] returns for it alone, its
    /// state advanced by exactly that step or, on error, untouched.
    ///
    /// `lanes` and `one` are workspaces of [`Layout::for_params`](hydrorattle::Layout)
    /// for this batch's parameters, `n` spheres and its bonds, in [`Lanes<K>`] and
    /// `f64`.
    ///
    /// # Errors
    /// [`BatchError::Length`] when a system does not have the batch's `n` spheres
    /// (nothing is stepped).
    pub fn step<E: Forces<K>>(
        &mut self,
        systems: [State<'_, f64>; K],
        lanes: &mut Workspace<'_, Lanes<K>>,
        one: &mut Workspace<'_, f64>,
        ext: &mut E,
    ) -> Result<[Result<StepReport<f64>, StepError>; K], BatchError> {
        for (system, s) in systems.iter().enumerate() {
            let len = s.len();
            if len != self.n {
                return Err(BatchError::Length {
                    system,
                    len,
                    expected: self.n,
                });
            }
        }
        self.pack(&systems);
        let mut time = Lanes(core::array::from_fn(|k| *systems[k].time));
        let state = State {
            pos: &mut self.pos,
            vel: &mut self.vel,
            omega: &mut self.omega,
            radius: &self.radius,
            density: &self.density,
            time: &mut time,
            noise: None,
        };
        clear_divergence();
        let mut add = |p: &[LV3<K>], r: &[Lanes<K>], f: &mut [LV3<K>]| ext.lanes(p, r, f);
        let result = hydrorattle::step_slices(state, &self.bonds, &self.params, lanes, &mut add);
        self.counts.lane_steps += 1;
        // The lanes to redo alone: those marked, or all when the step failed.
        let (redo, report) = match result {
            Ok(report) => (diverged(), Some(report)),
            Err(_) => (u64::MAX, None),
        };
        self.counts.diverged += u64::from(redo != 0 && report.is_some());
        self.counts.failed += u64::from(report.is_none());
        let mut k = 0;
        Ok(systems.map(|mut s| {
            let lane = k;
            k += 1;
            match report {
                Some(r) if redo >> lane & 1 == 0 => {
                    self.unpack(lane, &mut s, time);
                    Ok(lane_report(&r, lane))
                }
                _ => {
                    self.counts.fallback_steps += 1;
                    let mut add = |p: &[V3], r: &[f64], f: &mut [V3]| ext.system(lane, p, r, f);
                    let (b, p) = (&self.one_bonds[lane], &self.one_params[lane]);
                    hydrorattle::step_slices(s, b, p, one, &mut add)
                }
            }
        }))
    }

    /// The systems' states into the lanes.
    fn pack(&mut self, systems: &[State<'_, f64>; K]) {
        for (k, s) in systems.iter().enumerate() {
            for i in 0..self.n {
                self.pos[i].set_lane(k, s.pos[i].to_array());
                self.vel[i].set_lane(k, s.vel[i].to_array());
                self.omega[i].set_lane(k, s.omega[i].to_array());
                self.radius[i].0[k] = s.radius[i];
                self.density[i].0[k] = s.density[i];
            }
        }
    }

    /// Lane `k` back into its system's state.
    fn unpack(&self, k: usize, s: &mut State<'_, f64>, time: Lanes<K>) {
        for i in 0..self.n {
            s.pos[i] = V3::from_array(self.pos[i].lane(k));
            s.vel[i] = V3::from_array(self.vel[i].lane(k));
            s.omega[i] = V3::from_array(self.omega[i].lane(k));
        }
        *s.time = time.0[k];
    }
}

/// Lane `k`'s report.
fn lane_report<const K: usize>(r: &StepReport<Lanes<K>>, k: usize) -> StepReport<f64> {
    StepReport {
        iterations: r.iterations,
        velocity_iterations: r.velocity_iterations,
        residual: r.residual.0[k],
        max_tension: r.max_tension.0[k],
        contacts: r.contacts,
        wall_contacts: r.wall_contacts,
        contact_rounds: r.contact_rounds,
        noise_iterations: r.noise_iterations,
    }
}

/// The lanes' parameters: system `k`'s real values in lane `k` (each set's values
/// recorded in [`Params::map`]'s order, then replayed lane by lane), the rest system
/// 0's (equal in all, checked by the caller).
fn zip_params<const K: usize>(ps: [&Params<f64>; K]) -> Result<Params<Lanes<K>>, BatchError> {
    let bad = |system| move |_| BatchError::Params { system };
    let mut values: Vec<Vec<f64>> = Vec::with_capacity(K);
    for (k, p) in ps.iter().enumerate() {
        let mut v = Vec::new();
        p.map(|x| {
            v.push(x);
            x
        })
        .map_err(bad(k))?;
        values.push(v);
    }
    let mut i = 0;
    let lanes = ps[0]
        .map(|_| {
            let x = Lanes(core::array::from_fn(|k| values[k][i]));
            i += 1;
            x
        })
        .map_err(bad(0));
    // The box's checks decide per lane: clear what they raised.
    clear_divergence();
    lanes
}
