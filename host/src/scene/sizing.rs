//! How much kernel storage a run needs, and the limit a run must stay under.
//!
//! Every method stores the `N x N` mobility (packed 3x3 blocks), so storage grows as
//! `N^2`: 403 MB for 4096 beads overdamped in f64 (symmetric blocks, 48 bytes a pair;
//! 604 MB above a wall or in a box), 4.8 GB for the stable inertial method
//! with rotation. A scene file is checked against the limit from its counts alone,
//! while it is read and before any bead is generated or any pair checked, so an
//! oversized scene is refused at once, at the line that set its size.

use std::fmt;

use hydrorattle::{Contacts, Layout, Params};

use crate::scene::{Contact, Method, Precision, Scene, Solver, Thermal};

/// Default limit on one run's step storage (`run --max-storage`): 8 GiB holds every
/// method at 4096 beads in f64.
pub const DEFAULT_LIMIT: usize = 8 << 30;

/// Default limit on a run's trajectory files (`run --max-output`), bytes: 64 GiB.
pub const DEFAULT_OUTPUT_LIMIT: u64 = 64 << 30;

/// What a scene may ask for, checked while it is read: step storage and output size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Step storage, bytes.
    pub storage: usize,
    /// Trajectory files (extended XYZ, GSD, observables), bytes.
    pub output: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            storage: DEFAULT_LIMIT,
            output: DEFAULT_OUTPUT_LIMIT,
        }
    }
}

/// Bytes one trajectory frame of `n` particles takes at most, in every file of a run:
/// an extended XYZ line of 15 numbers of up to 24 characters per particle, 24 bytes
/// per particle in GSD, and a row of observables.
pub fn frame_bytes(n: usize) -> f64 {
    n as f64 * (15.0 * 24.0 + 24.0) + 600.0
}

/// Largest particle or bond count the storage arithmetic takes. Far beyond any limit
/// (storage there is about 1e17 bytes), and small enough that no count of the kernel's
/// [`Layout`] nor its byte total overflows.
const COUNT_MAX: usize = (usize::MAX >> 10).isqrt();

/// Whether the storage of `n` particles and `constraints` constraints (bonds,
/// contacts, wall rows) can be counted: both at most `(usize::MAX >> 10).isqrt()`,
/// below which no count of the kernel's layout nor its byte total overflows.
pub fn sizable(n: usize, constraints: usize) -> bool {
    n <= COUNT_MAX && constraints <= COUNT_MAX
}

/// A run whose step storage would exceed the limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooLarge {
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Bytes one step needs; `None` when a count is past counting.
    pub bytes: Option<usize>,
    /// The limit, bytes.
    pub limit: usize,
}

const GIB: f64 = (1u64 << 30) as f64;

impl fmt::Display for TooLarge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (n, b, limit) = (self.particles, self.bonds, human(self.limit as u64));
        match self.bytes {
            Some(bytes) => write!(
                f,
                "{n} particles and {b} bonds need {} of step storage, over the limit of {limit}",
                human(bytes as u64)
            )?,
            None => write!(
                f,
                "{n} particles and {b} bonds are too many to size (the limit is {limit})"
            )?,
        }
        write!(
            f,
            "; use fewer beads, precision \"f32\" (half the storage) or `run --max-storage`"
        )
    }
}

/// `bytes` in the largest binary unit that leaves at least 1.
pub fn human(bytes: u64) -> String {
    const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let (mut x, mut u) = (bytes as f64, 0);
    while x >= 1024.0 && u + 1 < UNITS.len() {
        x /= 1024.0;
        u += 1;
    }
    format!("{x:.1} {}", UNITS[u])
}

impl std::error::Error for TooLarge {}

/// What sizes a run's storage: method, rotation flag, solver and precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    /// Integrator.
    pub method: Method,
    /// Whether rotation is resolved.
    pub rotation: bool,
    /// Constraint solver.
    pub solver: Solver,
    /// Precision.
    pub precision: Precision,
    /// The contact model (hard contacts add constraint slots).
    pub contact: Option<Contact>,
    /// Thermal noise (adds the mobility's factor or the Lanczos basis).
    pub brownian: Option<Thermal>,
    /// A wall (one more constraint slot per particle).
    pub wall: bool,
    /// A slit (two more constraint slots per particle, one a wall).
    pub slit: bool,
    /// No stored mobility (`[integrator] matrix_free`).
    pub matrix_free: bool,
    /// The compact `f32` copy for the constraint products
    /// (`[integrator] compact_products`; storage where the kernel takes it).
    pub compact_products: bool,
    /// The box summed by PSE (`[box] method = "pse"`): the solver `"auto"` is Krylov
    /// (the kernel's `Params::solver_kind`).
    pub pse: bool,
    /// Stokesian dynamics' near field (`[near_field]`): its dense `6n x 6n` mobility
    /// and the far field's grand blocks.
    pub near: bool,
    /// Free space's fast product (`[free_space] method = "fast"`): matrix-free, its
    /// constraints by Krylov (the kernel's `Params::solver_kind`); `O(N)` storage.
    pub fast: bool,
}

impl Plan {
    /// A deterministic `f64` plan in free space with nothing beyond `method` and `solver`:
    /// no rotation, contacts, noise, wall, box, near field or fast product, the mobility
    /// stored. The other fields are public, to be set after.
    pub const fn free(method: Method, solver: Solver) -> Plan {
        Plan {
            method,
            rotation: false,
            solver,
            precision: Precision::F64,
            contact: None,
            brownian: None,
            wall: false,
            slit: false,
            matrix_free: false,
            compact_products: false,
            pse: false,
            near: false,
            fast: false,
        }
    }

    /// The plan of `scene` as it will run (its level already applied).
    pub fn of(scene: &Scene) -> Plan {
        Plan {
            method: scene.integrator.method,
            rotation: scene.model.rotation,
            solver: scene.integrator.solver,
            precision: scene.integrator.precision,
            contact: scene.contact,
            brownian: scene.brownian,
            wall: scene.wall.is_some(),
            slit: scene.slit.is_some(),
            matrix_free: scene.integrator.matrix_free,
            compact_products: scene.integrator.compact_products,
            pse: scene
                .periodic
                .is_some_and(|b| b.method == super::BoxMethod::Pse),
            near: scene.near_field.is_some(),
            fast: scene.free_space.is_some_and(|f| f.may_be_fast()),
        }
    }

    /// The kernel's storage for `n` particles and `b` bonds; `None` past counting.
    /// Sized by the kernel's own rule (`Layout::for_params`): hard contacts count as
    /// constraints beside the bonds.
    pub fn layout(&self, n: usize, b: usize) -> Option<Layout> {
        let contacts = self.contact.and_then(|c| c.hard_capacity(n));
        let surfaces = usize::from(self.wall) + 2 * usize::from(self.slit);
        let walls = n.saturating_mul(surfaces);
        let c = b
            .saturating_add(contacts.unwrap_or(0))
            .saturating_add(walls);
        sizable(n, c).then(|| Layout::for_params(&self.params(n), n, b))
    }

    /// The kernel's parameters of this plan for `n` particles: what sizes the storage
    /// and resolves the solver and the noise (any box, any near field, unit viscosity).
    pub fn params(&self, n: usize) -> Params<f64> {
        let mut p = Params::<f64>::new(1.0);
        p.method = self.method;
        p.rotation = self.rotation;
        p.solver.kind = self.solver;
        p.contacts = self
            .contact
            .and_then(|c| c.hard_capacity(n))
            .map(Contacts::new);
        p.wall = self.wall.then_some(hydrorattle::Wall::new(0.0));
        // Any slit: only its two surfaces size the storage.
        p.slit = self.slit.then_some(hydrorattle::Slit {
            floor: 0.0,
            ceiling: 1.0,
        });
        p.matrix_free = self.matrix_free || self.pse || self.fast;
        p.compact_products = self.compact_products;
        if self.pse {
            // Any box: only the solver's resolution reads it.
            p.periodic = hydrorattle::Periodic::new([1.0; 3]).ok();
            p.pse = Some(1e-3);
        }
        if self.fast && !self.pse && !self.wall && !self.slit {
            // Free space's fast product (no box): only its presence sizes the storage.
            p.pse = Some(1e-3);
        }
        if let Some(t) = self.brownian {
            p.brownian = Some(hydrorattle::Brownian {
                temperature: t.temperature,
                drift: t.drift,
            });
            p.noise_sqrt = t.sqrt;
        }
        // Any parameters: only whether it is on sizes the storage.
        if self.near {
            p.near = Some(hydrorattle::stokesian::NearField::default());
        }
        p
    }

    /// Bytes of [`layout`](Self::layout) in this plan's precision.
    pub fn bytes(&self, n: usize, b: usize) -> Option<usize> {
        self.layout(n, b).map(|l| match self.precision {
            Precision::F32 => l.bytes::<f32>(),
            Precision::F64 => l.bytes::<f64>(),
        })
    }

    /// The storage for `n` particles and `b` bonds, if it fits in `limit` bytes.
    pub fn check(&self, n: usize, b: usize, limit: usize) -> Result<Layout, TooLarge> {
        match (self.layout(n, b), self.bytes(n, b)) {
            (Some(layout), Some(bytes)) if bytes <= limit => Ok(layout),
            (_, bytes) => Err(TooLarge {
                particles: n,
                bonds: b,
                bytes,
                limit,
            }),
        }
    }
}

/// A limit given in GiB (`run --max-storage`) in bytes; `None` unless positive.
pub fn limit_from_gib(gib: f64) -> Option<usize> {
    // `as` saturates: a huge limit is just "no limit" up to the address space.
    (gib > 0.0).then_some((gib * GIB) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(method: Method, rotation: bool, precision: Precision) -> Plan {
        Plan {
            rotation,
            precision,
            ..Plan::free(method, Solver::Auto)
        }
    }

    #[test]
    fn every_method_fits_4096_beads_in_f64_under_the_default_limit() {
        for &method in Method::ALL {
            let p = plan(method, true, Precision::F64);
            assert!(p.check(4096, 4095, DEFAULT_LIMIT).is_ok(), "{method:?}");
        }
        // The mobility alone: tri(4096) symmetric blocks of 48 bytes.
        let od = plan(Method::Overdamped, false, Precision::F64);
        assert!(od.bytes(4096, 4095).unwrap() > 4096 * 4097 / 2 * 48);
    }

    #[test]
    fn counts_past_counting_are_refused_without_overflow() {
        let p = plan(Method::RattleStable, true, Precision::F64);
        let e = p.check(usize::MAX, usize::MAX - 1, usize::MAX).unwrap_err();
        assert_eq!(e.bytes, None);
        let sized = p.check(COUNT_MAX, COUNT_MAX, usize::MAX);
        assert!(
            sized.is_ok_and(|l| l.blocks > 0),
            "the largest count is sized"
        );
    }

    #[test]
    fn f32_needs_about_half_of_f64() {
        let (a, b) = (
            plan(Method::Overdamped, false, Precision::F32).bytes(1000, 999),
            plan(Method::Overdamped, false, Precision::F64).bytes(1000, 999),
        );
        let (a, b) = (a.unwrap() as f64, b.unwrap() as f64);
        assert!((a / b - 0.5).abs() < 0.01, "{a} / {b}");
    }

    #[test]
    fn sizes_read_in_binary_units() {
        assert_eq!(human(DEFAULT_LIMIT as u64), "8.0 GiB");
        assert_eq!(human(1536), "1.5 KiB");
        assert_eq!(human(12), "12.0 B");
        assert_eq!(human(u64::MAX), "16.0 EiB");
    }

    #[test]
    fn limits_in_gib() {
        assert_eq!(limit_from_gib(8.0), Some(DEFAULT_LIMIT));
        assert_eq!(limit_from_gib(0.0), None);
        assert_eq!(limit_from_gib(f64::NAN), None);
        assert_eq!(limit_from_gib(1e30), Some(usize::MAX));
    }
}
