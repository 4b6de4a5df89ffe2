//! A system ready to step: the particle state, bonds, kernel parameters, step storage,
//! noise generator and the scene's soft contact. The run loop and the Python package
//! step through [`Engine::step`], the one place in the host code that calls the kernel's
//! step.

use hydrorattle::{
    Bond, ExternalForce, Layout, Method, Noise, Params, Real, SoftContact, StepError, StepReport,
    forces,
};
use std::sync::Arc;

use hydrorattle_heap::Buffers;
use hydrorattle_parallel::Threads;

use super::lanczos::LanczosTally;
use super::retry::{self, Retries};
use super::{Beads, BuildError, bonds, params};
use crate::scene::free_cost::FreeChoice;
use crate::scene::free_reweigh::Reweigh;
use crate::scene::{DEFAULT_SEED, Overlap, Scene};
use crate::sizing::{Plan, TooLarge};

/// Extra forces added after gravity and the soft contact: `(positions, radii, forces)`,
/// called with candidate positions, possibly more than once per step.
pub type Extra<'a, T> = &'a mut dyn FnMut(&[<T as Real>::V3], &[T], &mut [<T as Real>::V3]);

/// The state, bonds, parameters and storage of one system in precision `T`. A clone is
/// an independent system in the same state (noise generator included).
#[derive(Clone)]
pub struct Engine<T: Real> {
    /// Particle state (positions, velocities, spins, radii, densities, time).
    pub beads: Beads<T>,
    /// Bonds (validated against the particles).
    pub bonds: Vec<Bond<T>>,
    /// Pin rows ([`Bond::pin`]: three per pinned sphere), solved after the bonds;
    /// empty without pinned spheres.
    pub pins: Vec<Bond<T>>,
    /// The step's constraint list when there are pins: the bonds, then the pins
    /// (rebuilt each step from both, so that neither can go stale).
    rows: Vec<Bond<T>>,
    /// Kernel parameters.
    pub params: Params<T>,
    /// Thermal noise generator (drawn from only when `params.brownian` is on).
    pub noise: Noise,
    /// The soft contact force, when the scene asks for one.
    pub contact: Option<SoftContact<T>>,
    /// Steps refused and completed as split steps so far ([`retry`]).
    pub retries: Retries,
    /// The thermal noise's Lanczos iterations so far ([`LanczosTally`]; empty without
    /// a temperature).
    pub lanczos: LanczosTally,
    store: Buffers<T>,
    /// The multipliers of the last accepted step ([`Engine::tensions`]).
    pub(super) multipliers: Vec<T>,
    /// The pool for the mobility's bands (shared by copies of the system).
    pub(super) threads: Option<Arc<Threads>>,
    /// PSE's arrays (complex, indices, vectors) when the box is summed by PSE
    /// ([`hydrorattle::integrate::pse_storage`]); empty otherwise.
    pse: (Vec<[T; 2]>, Vec<usize>, Vec<T::V3>),
    /// The fast free-space product's kernel transform (reals) when the scene runs on it
    /// ([`hydrorattle::integrate::fast_storage`]; its grid and cell list in `pse`'s
    /// complex values and indices, with rotation the spins' vectors in its vectors);
    /// empty otherwise.
    fast: Vec<T>,
    /// With `[free_space] reweigh` on the fast product: the weighing made before each
    /// step ([`Engine::pair_params`] where the pair sums are cheaper).
    reweigh: Option<Box<Reweigh>>,
    /// Steps taken on the pair sums in place of the fast product ([`Reweigh`]).
    pub pair_steps: u64,
    /// Whether the last step weighed took the pair sums (for the log of each change).
    on_pairs: bool,
}

impl<T: Real> Engine<T> {
    /// The system of `scene` (its level already applied): particles and bonds checked,
    /// storage sized for its method and refused beyond `limit` bytes before any
    /// `O(N^2)` work.
    pub fn new(scene: &Scene, limit: usize) -> Result<Self, BuildError> {
        let p = params::<T>(scene);
        let pins = crate::scene::pins::<T>(scene);
        let (n, b) = (scene.particles.len(), scene.bonds.len() + pins.len());
        // The plan sizes thermal noise too (the factor or the Lanczos basis).
        let layout = Plan::of(scene).check(n, b, limit)?;
        let beads = crate::scene::beads::<T>(&scene.particles, 1.0)?;
        beads.check_pairs(scene.model.overlap == Overlap::Allow, p.periodic.as_ref())?;
        let bonds = bonds::<T>(&scene.bonds, n)?;
        let noise = Noise::new(scene.brownian.map_or(DEFAULT_SEED, |b| b.seed));
        let contact = scene.contact.and_then(|c| c.soft()).map(|k| SoftContact {
            stiffness: T::from_f64(k),
        });
        let mut e = Self::with_layout(beads, bonds, p, noise, contact, layout, limit)?;
        hydrorattle::bonds::validate(&pins, n)?;
        e.pins = pins;
        if scene.free_space.is_some_and(|f| f.reweighs()) {
            e.reweighing();
        }
        Ok(e)
    }

    /// Weighs the fast product against the pair sums before each step
    /// ([`Reweigh`]). Nothing where the step does not take the fast product.
    pub(super) fn reweighing(&mut self) {
        let b = self.bonds.len() + self.pins.len();
        self.reweigh = Reweigh::new(&self.params, b).map(Box::new);
    }

    /// The pair sums' parameters for a step of this system on the fast product: no
    /// fast product, the constraints by the solver it resolved. The kernel sizes their
    /// storage as the fast product's (`Layout::for_params` reads neither the product
    /// nor a solver it does not resolve to), so the system's storage holds them.
    fn pair_params(&self) -> Params<T> {
        let (n, b) = (self.beads.len(), self.bonds.len() + self.pins.len());
        let mut pairs = self.params;
        pairs.pse = None;
        pairs.solver.kind = self.params.solver_kind(n, b);
        pairs
    }

    /// Whether the system weighs the fast product against the pair sums before each
    /// step ([`Reweigh`]).
    pub fn reweighs(&self) -> bool {
        self.reweigh.is_some()
    }

    /// A system from its parts (checked by the caller), with storage sized by the
    /// kernel's rule for `params` ([`Layout::for_params`]), refused beyond `limit`
    /// bytes.
    pub fn from_parts(
        beads: Beads<T>,
        bonds: Vec<Bond<T>>,
        params: Params<T>,
        noise: Noise,
        contact: Option<SoftContact<T>>,
        limit: usize,
    ) -> Result<Self, BuildError> {
        Self::from_rows(beads, bonds, Vec::new(), params, noise, contact, limit)
    }

    /// [`Engine::from_parts`] with pin rows (checked by the caller), sized for the
    /// bonds and the pins together as [`Engine::new`] sizes a scene's.
    pub(super) fn from_rows(
        beads: Beads<T>,
        bonds: Vec<Bond<T>>,
        pins: Vec<Bond<T>>,
        params: Params<T>,
        noise: Noise,
        contact: Option<SoftContact<T>>,
        limit: usize,
    ) -> Result<Self, BuildError> {
        let (n, b) = (beads.len(), bonds.len() + pins.len());
        // Counted as the scenes' plan counts them (saturating), before the kernel's
        // layout arithmetic, which a contact capacity of 2^62 would overflow.
        let capacity = params.contacts.map_or(0, |c| c.capacity);
        let walls = if params.wall.is_some() { n } else { 0 };
        if !crate::sizing::sizable(n, b.saturating_add(capacity).saturating_add(walls)) {
            return Err(TooLarge {
                particles: n,
                bonds: b,
                bytes: None,
                limit,
            }
            .into());
        }
        let layout = Layout::for_params(&params, n, b);
        let mut e = Self::with_layout(beads, bonds, params, noise, contact, layout, limit)?;
        e.pins = pins;
        Ok(e)
    }

    /// Storage for `layout`, within `limit` bytes.
    fn with_layout(
        beads: Beads<T>,
        bonds: Vec<Bond<T>>,
        params: Params<T>,
        noise: Noise,
        contact: Option<SoftContact<T>>,
        layout: Layout,
        limit: usize,
    ) -> Result<Self, BuildError> {
        let (n, b) = (beads.len(), bonds.len());
        // PSE's grid and cell list, from the parameters the step derives (parameters it
        // refuses leave none: the first step then refuses them, typed).
        let pse = hydrorattle::integrate::pse_storage(&params, &beads.radius);
        let pse = pse
            .ok()
            .flatten()
            .unwrap_or(hydrorattle::mobility::pse::PseSize {
                complex: 0,
                index: 0,
                vectors: 0,
            });
        // Or the fast free-space product's, sized from the first configuration (the
        // step keeps within them as the cloud moves: the kernel's `src/geometry/free/fast.rs`).
        let fast = hydrorattle::integrate::fast_storage(&params, &beads.pos, &beads.radius);
        let (pse, fast) = match fast.ok().flatten() {
            Some(f) => (
                hydrorattle::mobility::pse::PseSize {
                    complex: f.complex,
                    index: f.index,
                    // The spins' scratch with rotation.
                    vectors: hydrorattle::integrate::fast_vectors(&params, n),
                },
                f.reals,
            ),
            None => (pse, 0),
        };
        let real = std::mem::size_of::<T>();
        let pse_bytes = pse.complex * 2 * real + pse.index * 8 + pse.vectors * 3 * real;
        let pse_bytes = pse_bytes + fast * real;
        let bytes = layout.bytes::<T>() + pse_bytes;
        if bytes > limit {
            return Err(TooLarge {
                particles: n,
                bonds: b,
                bytes: Some(bytes),
                limit,
            }
            .into());
        }
        let store = Buffers::try_new(layout).map_err(|_| BuildError::OutOfMemory(bytes))?;
        Ok(Engine {
            beads,
            bonds,
            pins: Vec::new(),
            rows: Vec::new(),
            params,
            noise,
            contact,
            retries: Retries::default(),
            lanczos: LanczosTally::default(),
            store,
            multipliers: Vec::new(),
            threads: None,
            pse: (
                vec![[T::ZERO; 2]; pse.complex],
                vec![0; pse.index],
                vec![T::V3_ZERO; pse.vectors],
            ),
            fast: vec![T::ZERO; fast],
            reweigh: None,
            pair_steps: 0,
            on_pairs: false,
        })
    }

    /// This system with `threads` threads (0: every core) for the mobility's bands where
    /// the kernel cuts it into bands ([`hydrorattle::parallel::BANDED_MIN`] beads on);
    /// smaller systems stay on the calling thread. The bits do not depend on it.
    pub fn with_threads(mut self, threads: usize) -> std::io::Result<Self> {
        let banded = hydrorattle::parallel::bands(self.beads.len()) > 1;
        self.threads = match banded && threads != 1 {
            true => Some(Arc::new(Threads::new(threads)?)),
            false => None,
        };
        Ok(self)
    }

    /// The checks the kernel's step makes of its inputs (parameters, particles, bonds,
    /// thermal noise, contacts, wall, box: [`hydrorattle::check_step`]) and of every
    /// pair (nested or coincident spheres; overlapping ones unless
    /// [`Params::allow_overlap`]; in a periodic box through the minimum image), without
    /// stepping. A front end asks it when it builds
    /// a system, so that what the first step would refuse (`dt = 0`, spheres
    /// overlapping at the start) is refused there, as a parameter error.
    pub fn check(&mut self) -> Result<(), StepError> {
        let cell = self.params.periodic.as_ref();
        self.beads.check_pairs(self.params.allow_overlap, cell)?;
        let mut state = self.beads.state();
        state.noise = Some(&mut self.noise);
        let rows = match self.pins.is_empty() {
            true => &self.bonds[..],
            false => {
                self.rows.clear();
                self.rows.extend_from_slice(&self.bonds);
                self.rows.extend_from_slice(&self.pins);
                &self.rows[..]
            }
        };
        hydrorattle::check_step(&state, rows, &self.params)
    }

    /// One step with the scene's forces only.
    pub fn step(&mut self) -> Result<StepReport<T>, StepError> {
        self.step_with(&mut |_: &[T::V3], _: &[T], _: &mut [T::V3]| {})
    }

    /// One step, `extra` adding forces after gravity and the soft contact; a step the
    /// kernel refuses is retried split (along a Brownian bridge at temperature,
    /// [`retry`]).
    /// A failed step leaves the state and the noise generator as they were.
    pub fn step_with(&mut self, extra: Extra<'_, T>) -> Result<StepReport<T>, StepError> {
        let contact = self.contact;
        // The path of this step, weighed on the spheres as they start it: the pair
        // sums first where they are cheaper, the fast product after them should the
        // kernel refuse them (their noise's Lanczos run past its cap, which the model
        // misjudges on a stretched cloud); a refused step leaves the state as it was.
        let sums = self.reweigh.as_deref().and_then(|w| {
            let choice = w.choose(&self.beads.pos, &self.beads.radius);
            (choice == FreeChoice::MatrixFree).then(|| self.pair_params())
        });
        if self.reweigh.is_some() && sums.is_some() != self.on_pairs {
            self.on_pairs = sums.is_some();
            let path = ["the fast product", "the pair sums"][usize::from(self.on_pairs)];
            log::debug!("t = {:?}: stepping on {path}", self.beads.time.to_f64());
        }
        let mut ext = |pos: &[T::V3], radius: &[T], force: &mut [T::V3]| {
            if let Some(mut c) = contact {
                c.add(pos, radius, force);
            }
            extra(pos, radius, force);
        };
        let ws = match &self.threads {
            Some(pool) => self.store.workspace().with_parallel(pool.as_ref()),
            None => self.store.workspace(),
        };
        let (c, i, v) = &mut self.pse;
        let mut ws = match self.fast.is_empty() {
            true => ws.with_pse(c, i, v),
            false => ws.with_fast(c, &mut self.fast, i).with_fast_vectors(v),
        };
        if !self.pins.is_empty() {
            self.rows.clear();
            self.rows.extend_from_slice(&self.bonds);
            self.rows.extend_from_slice(&self.pins);
        }
        let rows = match self.pins.is_empty() {
            true => &self.bonds[..],
            false => &self.rows[..],
        };
        let mut attempt = |params: &Params<T>| {
            retry::step(
                &mut self.beads,
                rows,
                params,
                &mut ws,
                &mut ext,
                &mut self.noise,
                retry::Counters {
                    retries: &mut self.retries,
                    lanczos: &mut self.lanczos,
                },
            )
        };
        let (report, on_sums) = match sums.map(|p| attempt(&p)) {
            Some(Ok(r)) => (r, true),
            _ => (attempt(&self.params)?, false),
        };
        // The multipliers are the workspace's until the next step, which may fail and
        // leave them partial: keep the accepted step's.
        self.multipliers.clear();
        self.multipliers
            .extend_from_slice(ws.multipliers(rows.len()));
        self.pair_steps += u64::from(on_sums);
        Ok(report)
    }

    /// The total force the pins exert on the pinned spheres after the last accepted
    /// step (`sum lambda s e` over the pin rows), `None` before the first step,
    /// without pins, and for `Overdamped2` (its last projection's multipliers are a
    /// correction to the predictor's, as for [`Engine::tensions`]). At rest it carries
    /// the buoyant weight of everything on them.
    pub fn pin_load(&self) -> Option<[T; 3]> {
        let first = self.bonds.len();
        let rows = first + self.pins.len();
        let method = self.params.method;
        if self.pins.is_empty() || self.multipliers.len() != rows || method == Method::Overdamped2 {
            return None;
        }
        let mut f = [T::ZERO; 3];
        for (b, &l) in self.pins.iter().zip(&self.multipliers[first..]) {
            f[b.axis()] += l * b.length;
        }
        Some(f)
    }

    /// The tension of every bond after the last accepted step (force; positive when the
    /// bond pulls its ends together), `None` before the first step and for
    /// `Overdamped2`, whose final projection's multipliers are only a correction to the
    /// predictor's.
    /// * Rigid bonds: `-lambda_k d_k`, the constraint force `f_i = lambda_k (r_i - r_j)`
    ///   along the bond (the kernel's `max_tension` is the largest magnitude).
    /// * Springs: the spring law (Hookean or FENE) at the current length, from the
    ///   kernel's [`hydrorattle::forces::springs`].
    pub fn tensions(&self) -> Option<Vec<T>> {
        match self.params.method {
            Method::Overdamped2 => None,
            Method::Springs => self.spring_tensions(),
            _ if self.multipliers.len() != self.bonds.len() + self.pins.len() => None,
            _ => Some(
                self.bonds
                    .iter()
                    .zip(&self.multipliers)
                    .map(|(b, &l)| -l * b.length)
                    .collect(),
            ),
        }
    }

    /// Each spring's force along its bond at the current positions.
    fn spring_tensions(&self) -> Option<Vec<T>> {
        let (p, pos) = (&self.params, &self.beads.pos);
        self.bonds
            .iter()
            .map(|b| {
                let ends = [pos[b.i], pos[b.j]];
                let one = [Bond { i: 0, j: 1, ..*b }];
                let mut f = [T::V3_ZERO; 2];
                forces::springs(&one, p.spring_stiffness, p.fene, &ends, &mut f).ok()?;
                let r = ends[0] - ends[1];
                Some(-T::dot(f[0], r) / T::norm(r))
            })
            .collect()
    }
}
