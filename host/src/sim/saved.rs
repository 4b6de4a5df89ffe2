//! A whole system as plain data: the state, bonds, every kernel parameter, the noise
//! generator, the soft contact, the counters and the last step's multipliers, each
//! float as the bits of its `f64` value (`f32` widens exactly). What the Python package
//! pickles and copies between processes: a restored system continues with the same
//! bits as the original (checkpoints keep the state only; the parameters come from
//! their scene there).

use hydrorattle::{
    Bond, Brownian, Contacts, Drift, Hydro, Lanczos, Method, Named, Noise, NoiseSqrt, Params,
    Periodic, Real, SoftContact, Solver, SolverKind, Wall,
};
use serde::{Deserialize, Serialize};

use super::{Beads, Engine, LanczosTally, retry::Retries};
use crate::scene::Precision;
use crate::sizing::DEFAULT_LIMIT;

/// Format version of [`Saved`].
const VERSION: u32 = 1;

/// The parameters, floats as `f64` bits, names as the kernel's ([`Named`]). A key
/// no system writes is a corrupt record (refused, not ignored).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedParams {
    dt: u64,
    viscosity: u64,
    fluid_density: u64,
    gravity: [u64; 3],
    flow_velocity: [u64; 3],
    vorticity: [u64; 3],
    hydro: String,
    method: String,
    rotation: bool,
    matrix_free: bool,
    /// Absent in systems saved before the key (false).
    #[serde(default)]
    compact_products: bool,
    solver: String,
    tolerance: u64,
    max_iterations: u32,
    allow_overlap: bool,
    spring_stiffness: u64,
    fene: Option<u64>,
    stability_guard: bool,
    brownian: Option<(u64, String)>,
    noise_sqrt: String,
    lanczos: (u64, u32),
    contacts: Option<(usize, u32)>,
    wall: Option<u64>,
    periodic: Option<[u64; 3]>,
    resolve_tensions: bool,
    /// Stokesian dynamics' near field: cutoff, wall cutoff, minimum gap. Absent in
    /// systems saved before the key, and without a near field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    near: Option<[u64; 3]>,
    /// The fast product's tolerance (`Params::pse`: PSE in a box, the fast free-space
    /// product without one). Absent in systems saved before the key, and without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pse: Option<u64>,
    /// A slit's floor and ceiling. Absent in systems saved before the key, and without
    /// a slit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    slit: Option<[u64; 2]>,
}

/// A system as plain data ([`Engine::save`], [`Engine::restore`]); unknown keys are
/// refused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Saved {
    version: u32,
    /// The precision the system steps in.
    pub precision: Precision,
    pos: Vec<u64>,
    vel: Vec<u64>,
    omega: Vec<u64>,
    radius: Vec<u64>,
    density: Vec<u64>,
    time: u64,
    bonds: Vec<(usize, usize, u64)>,
    /// The pin rows of fixed spheres ([`Engine::pins`]); absent in systems saved
    /// before the key (none).
    #[serde(default)]
    pins: Vec<(usize, usize, u64)>,
    params: SavedParams,
    noise: [u64; 6],
    contact: Option<u64>,
    retries: Retries,
    lanczos: LanczosTally,
    multipliers: Vec<u64>,
    threads: usize,
    /// Whether the system weighs the fast product against the pair sums before each
    /// step ([`Engine::reweighs`]); absent where it does not (and in systems saved
    /// before the key).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    reweigh: bool,
    /// Steps taken on the pair sums by a system that weighs (absent: none).
    #[serde(default, skip_serializing_if = "none")]
    pair_steps: u64,
}

/// Whether a count is zero (left out of the record).
fn none(k: &u64) -> bool {
    *k == 0
}

fn b<T: Real>(x: T) -> u64 {
    x.to_f64().to_bits()
}

fn f<T: Real>(bits: u64) -> T {
    T::from_f64(f64::from_bits(bits))
}

fn b3<T: Real>(v: T::V3) -> [u64; 3] {
    T::v3_to_f64(v).map(f64::to_bits)
}

fn f3<T: Real>(v: [u64; 3]) -> T::V3 {
    T::v3_from(v.map(f64::from_bits))
}

/// A kernel name back to its value; a name no value has is a corrupt record.
fn named<X: Named>(s: &str) -> Result<X, String> {
    X::from_name(s).map_err(|e| format!("saved system: {e}"))
}

impl SavedParams {
    fn of<T: Real>(p: &Params<T>) -> Self {
        SavedParams {
            dt: b(p.dt),
            viscosity: b(p.viscosity),
            fluid_density: b(p.fluid_density),
            gravity: b3::<T>(p.gravity),
            flow_velocity: b3::<T>(p.flow_velocity),
            vorticity: b3::<T>(p.vorticity),
            hydro: p.hydro.name().into(),
            method: p.method.name().into(),
            rotation: p.rotation,
            matrix_free: p.matrix_free,
            compact_products: p.compact_products,
            solver: p.solver.kind.name().into(),
            tolerance: b(p.solver.tolerance),
            max_iterations: p.solver.max_iterations,
            allow_overlap: p.allow_overlap,
            spring_stiffness: b(p.spring_stiffness),
            fene: p.fene.map(b),
            stability_guard: p.stability_guard,
            brownian: p
                .brownian
                .map(|x| (b(x.temperature), x.drift.name().into())),
            noise_sqrt: p.noise_sqrt.name().into(),
            lanczos: (b(p.lanczos.tolerance), p.lanczos.max_iterations),
            contacts: p.contacts.map(|c| (c.capacity, c.max_rounds)),
            wall: p.wall.map(|w| b(w.height)),
            periodic: p.periodic.map(|c| c.size().map(b)),
            resolve_tensions: p.resolve_tensions,
            near: p
                .near
                .map(|n| [b(n.cutoff), b(n.wall_cutoff), b(n.min_gap)]),
            pse: p.pse.map(f64::to_bits),
            slit: p.slit.map(|s| [b(s.floor), b(s.ceiling)]),
        }
    }

    fn params<T: Real>(&self) -> Result<Params<T>, String> {
        let mut p = Params::new(f(self.dt));
        p.viscosity = f(self.viscosity);
        p.fluid_density = f(self.fluid_density);
        p.gravity = f3::<T>(self.gravity);
        p.flow_velocity = f3::<T>(self.flow_velocity);
        p.vorticity = f3::<T>(self.vorticity);
        p.hydro = named::<Hydro>(&self.hydro)?;
        p.method = named::<Method>(&self.method)?;
        p.rotation = self.rotation;
        p.matrix_free = self.matrix_free;
        p.compact_products = self.compact_products;
        p.solver = Solver {
            kind: named::<SolverKind>(&self.solver)?,
            tolerance: f(self.tolerance),
            max_iterations: self.max_iterations,
        };
        p.allow_overlap = self.allow_overlap;
        p.spring_stiffness = f(self.spring_stiffness);
        p.fene = self.fene.map(f);
        p.stability_guard = self.stability_guard;
        p.brownian = match &self.brownian {
            Some((t, drift)) => Some(Brownian {
                temperature: f(*t),
                drift: named::<Drift>(drift)?,
            }),
            None => None,
        };
        p.noise_sqrt = named::<NoiseSqrt>(&self.noise_sqrt)?;
        p.lanczos = Lanczos {
            tolerance: f(self.lanczos.0),
            max_iterations: self.lanczos.1,
        };
        p.contacts = self.contacts.map(|(capacity, max_rounds)| Contacts {
            capacity,
            max_rounds,
        });
        p.wall = self.wall.map(|h| Wall::new(f(h)));
        p.slit = self.slit.map(|[l, h]| hydrorattle::Slit {
            floor: f(l),
            ceiling: f(h),
        });
        p.periodic = match self.periodic {
            Some(s) => Some(Periodic::new(s.map(f)).map_err(|e| format!("saved system: {e}"))?),
            None => None,
        };
        p.resolve_tensions = self.resolve_tensions;
        p.near = self
            .near
            .map(|[c, w, g]| hydrorattle::stokesian::NearField {
                cutoff: f(c),
                wall_cutoff: f(w),
                min_gap: f(g),
            });
        // Checked on load with the rest ([`Engine::check`]: the step's own checks).
        p.pse = self.pse.map(f64::from_bits);
        Ok(p)
    }
}

impl<T: Real> Engine<T> {
    /// This system as plain data, in `precision` (the caller's name for `T`).
    pub fn save(&self, precision: Precision) -> Saved {
        let v3 = |v: &[T::V3]| v.iter().flat_map(|&x| b3::<T>(x)).collect();
        let s = |v: &[T]| v.iter().map(|&x| b(x)).collect();
        let beads = &self.beads;
        Saved {
            version: VERSION,
            precision,
            pos: v3(&beads.pos),
            vel: v3(&beads.vel),
            omega: v3(&beads.omega),
            radius: s(&beads.radius),
            density: s(&beads.density),
            time: b(beads.time),
            bonds: self.bonds.iter().map(|x| (x.i, x.j, b(x.length))).collect(),
            pins: self.pins.iter().map(|x| (x.i, x.j, b(x.length))).collect(),
            params: SavedParams::of(&self.params),
            noise: self.noise.save(),
            contact: self.contact.map(|c| b(c.stiffness)),
            retries: self.retries,
            lanczos: self.lanczos,
            multipliers: s(&self.multipliers),
            threads: self.threads.as_ref().map_or(1, |t| t.threads()),
            reweigh: self.reweighs(),
            pair_steps: self.pair_steps,
        }
    }

    /// The system [`Engine::save`] saved (its storage allocated again); an error for a
    /// record no system saves (another version, a name or generator state no system
    /// has, arrays of the wrong lengths, multipliers for other than its bonds), and for
    /// what a system's construction refuses ([`Engine::check`]: parameters, particles,
    /// bonds, pairs), so that a damaged record fails here, not at its first step.
    pub fn restore(s: &Saved) -> Result<Self, String> {
        if s.version != VERSION {
            return Err(format!(
                "saved system: version {} (this build reads {VERSION})",
                s.version
            ));
        }
        let n = s.radius.len();
        let lengths = [s.pos.len(), s.vel.len(), s.omega.len()];
        if lengths.iter().any(|&l| l != 3 * n) || s.density.len() != n {
            return Err("saved system: arrays of unequal lengths".into());
        }
        let v3 = |v: &[u64]| -> Vec<T::V3> {
            v.chunks_exact(3)
                .map(|c| f3::<T>([c[0], c[1], c[2]]))
                .collect()
        };
        let beads = Beads {
            pos: v3(&s.pos),
            vel: v3(&s.vel),
            omega: v3(&s.omega),
            radius: s.radius.iter().map(|&x| f(x)).collect(),
            density: s.density.iter().map(|&x| f(x)).collect(),
            time: f(s.time),
            noise: None,
        };
        let bonds: Vec<Bond<T>> = s
            .bonds
            .iter()
            .map(|&(i, j, l)| Bond { i, j, length: f(l) })
            .collect();
        hydrorattle::bonds::validate(&bonds, n).map_err(|e| e.to_string())?;
        let noise = Noise::restore(s.noise).ok_or("saved system: not a generator's state")?;
        let contact = s.contact.map(|k| SoftContact { stiffness: f(k) });
        let params = s.params.params::<T>()?;
        let pins: Vec<Bond<T>> = s
            .pins
            .iter()
            .map(|&(i, j, l)| Bond { i, j, length: f(l) })
            .collect();
        if pins.iter().any(|p| !p.is_pin()) {
            return Err("saved system: a pin row that pins nothing".into());
        }
        hydrorattle::bonds::validate(&pins, n).map_err(|e| format!("saved system: {e}"))?;
        let mut e = Engine::from_rows(beads, bonds, pins, params, noise, contact, DEFAULT_LIMIT)
            .map_err(|e| e.to_string())?;
        // None before a first step, else one per constraint row (bonds, then pins).
        let rows = e.bonds.len() + e.pins.len();
        if !(s.multipliers.is_empty() || s.multipliers.len() == rows) {
            return Err(format!(
                "saved system: {} multipliers for {rows} constraint rows",
                s.multipliers.len()
            ));
        }
        // A saved state is one a step accepted: with hard contacts, spheres touch to
        // within the solver's tolerance, which the check of a new system's start would
        // call an overlap. Nested and coincident spheres are refused all the same.
        let allow = e.params.allow_overlap;
        e.params.allow_overlap = allow || e.params.contacts.is_some();
        let checked = e.check();
        e.params.allow_overlap = allow;
        checked.map_err(|k| format!("saved system: {k}"))?;
        e.retries = s.retries;
        e.lanczos = s.lanczos;
        e.multipliers = s.multipliers.iter().map(|&x| f(x)).collect();
        if s.reweigh {
            e.reweighing();
        }
        e.pair_steps = s.pair_steps;
        e.with_threads(s.threads).map_err(|e| e.to_string())
    }
}
