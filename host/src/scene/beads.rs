//! A scene in the kernel's terms: runtime-sized particle state and bonds (what the
//! kernel's `step_slices` advances, for any number of beads) and the step's
//! parameters, in either precision. The run ([`crate::sim`]) and the scene's own
//! check against the kernel's first step ([`super::kernel`]) both build from here.

use std::fmt;

use hydrorattle::{Bond, BondError, Params, ParticleError, Real, Solver};

use super::sizing::TooLarge;
use crate::scene::{self, Scene};

/// Particle state in vectors of any length (all of the same length): the heap
/// crate's [`Spheres`](hydrorattle_heap::Spheres). Its `noise` stays `None`: an
/// engine keeps its generator itself ([`Engine::noise`](crate::sim::Engine::noise)).
pub type Beads<T> = hydrorattle_heap::Spheres<T>;

/// The particles with their initial velocities, densities scaled by `density_scale`,
/// each checked on its own in precision `T` (finite, radius > 0, density >= 0; pairs
/// are [`Beads::check_pairs`]' job).
pub fn beads<T: Real>(
    particles: &[scene::Particle],
    density_scale: f64,
) -> Result<Beads<T>, ParticleError> {
    let n = particles.len();
    let mut beads = Beads {
        pos: Vec::with_capacity(n),
        vel: vec![T::V3_ZERO; n],
        omega: vec![T::V3_ZERO; n],
        radius: Vec::with_capacity(n),
        density: Vec::with_capacity(n),
        time: T::ZERO,
        noise: None,
    };
    for (k, q) in particles.iter().enumerate() {
        let (r, d) = (
            T::from_f64(q.radius),
            T::from_f64(q.density * density_scale),
        );
        let pos = T::v3_from(q.position);
        let mut kp = hydrorattle::Particle::new(pos, r, d);
        kp.velocity = T::v3_from(q.velocity);
        // Values valid in f64 may not be in f32 (an overflow, a radius that rounds to 0).
        hydrorattle::particles::check_one(k, &kp)?;
        beads.vel[k] = kp.velocity;
        beads.omega[k] = T::v3_from(q.angular_velocity);
        beads.pos.push(pos);
        beads.radius.push(r);
        beads.density.push(d);
    }
    Ok(beads)
}

/// A scene's bonds in precision `T`, validated against `n` particles (range,
/// self-bonds, lengths, duplicates).
pub fn bonds<T: Real>(bonds: &[scene::Bond], n: usize) -> Result<Vec<Bond<T>>, BondError> {
    let out: Vec<Bond<T>> = bonds
        .iter()
        .map(|b| Bond {
            i: b.i,
            j: b.j,
            length: T::from_f64(b.length),
        })
        .collect();
    hydrorattle::bonds::validate(&out, n)?;
    Ok(out)
}

/// The kernel's pin rows of `scene`: three per pinned sphere ([`Bond::pins`], the
/// sphere's radius as their scale), to follow the bonds in the step's list.
pub fn pins<T: Real>(scene: &Scene) -> Vec<Bond<T>> {
    let radius = |k: usize| T::from_f64(scene.particles.get(k).map_or(1.0, |p| p.radius));
    scene
        .pinned
        .iter()
        .flat_map(|&k| Bond::pins(k, radius(k)))
        .collect()
}

/// Why a run cannot start: the kernel refuses a particle or a bond, or the storage
/// would exceed the limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BuildError {
    /// A particle, on its own or in a pair.
    Particle(ParticleError),
    /// A bond.
    Bond(BondError),
    /// The step storage.
    TooLarge(TooLarge),
    /// The system refused the step storage's memory (bytes asked for).
    OutOfMemory(usize),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Particle(e) => write!(f, "{e}"),
            BuildError::Bond(e) => write!(f, "{e}"),
            BuildError::TooLarge(e) => write!(f, "{e}"),
            BuildError::OutOfMemory(bytes) => {
                write!(f, "the system refused {bytes} bytes for the step storage")
            }
        }
    }
}

impl std::error::Error for BuildError {}

impl From<ParticleError> for BuildError {
    fn from(e: ParticleError) -> Self {
        BuildError::Particle(e)
    }
}

impl From<BondError> for BuildError {
    fn from(e: BondError) -> Self {
        BuildError::Bond(e)
    }
}

impl From<TooLarge> for BuildError {
    fn from(e: TooLarge) -> Self {
        BuildError::TooLarge(e)
    }
}

/// Kernel parameters for a scene in precision `T`.
pub fn params<T: Real>(scene: &Scene) -> Params<T> {
    let i = &scene.integrator;
    let mut p = Params::new(T::from_f64(i.dt));
    p.viscosity = T::from_f64(scene.fluid.viscosity);
    p.fluid_density = T::from_f64(scene.fluid.density);
    p.gravity = T::v3_from(scene.gravity);
    p.flow_velocity = T::v3_from(scene.flow.velocity);
    p.vorticity = T::v3_from(scene.flow.vorticity);
    p.hydro = scene.model.hydrodynamics;
    p.method = i.method;
    p.rotation = scene.model.rotation;
    p.matrix_free = i.matrix_free;
    p.compact_products = i.compact_products;
    // f32 cannot reach 1e-10: floor the tolerance at a few hundred ulps.
    let floor = 256.0 * T::EPSILON.to_f64();
    p.solver = Solver {
        kind: i.solver,
        tolerance: T::from_f64(i.tolerance.max(floor)),
        max_iterations: u32::try_from(i.max_iterations).unwrap_or(u32::MAX),
    };
    // `overlap` is about t = 0 (checked when the scene is read and when the run is
    // prepared); during the run spheres may come to overlap, as in the paper.
    p.allow_overlap = true;
    p.spring_stiffness = T::from_f64(i.stiffness);
    p.fene = i.fene.map(T::from_f64);
    // The paper's explicit drag can shiver silently (bounded, wrong) beyond its limit:
    // the demo refuses such steps up front.
    p.stability_guard = true;
    p.contacts = scene
        .contact
        .and_then(|c| c.hard_capacity(scene.particles.len()))
        .map(hydrorattle::Contacts::new);
    p.brownian = scene.brownian.map(|b| hydrorattle::Brownian {
        temperature: T::from_f64(b.temperature),
        drift: b.drift,
    });
    if let Some(b) = scene.brownian {
        p.noise_sqrt = b.sqrt;
    }
    p.wall = scene
        .wall
        .map(|w| hydrorattle::Wall::new(T::from_f64(w.height)));
    p.slit = scene.slit.map(|s| hydrorattle::Slit {
        floor: T::from_f64(s.floor),
        ceiling: T::from_f64(s.ceiling),
    });
    // The scene checked the edges (finite, > 0) in f64; one that overflows `T` is
    // left out here and refused by the scene's check against the first step.
    p.periodic = scene
        .periodic
        .and_then(|b| hydrorattle::Periodic::new(b.size.map(T::from_f64)).ok());
    // PSE where the scene names it or the run resolved to it
    // (`Scene::with_box_resolved`); "auto" left unresolved is the Ewald path. PSE
    // gives products only: its steps are matrix-free.
    p.pse = scene
        .periodic
        .filter(|b| b.method == scene::BoxMethod::Pse)
        .map(|b| b.tolerance);
    // Free space's fast product: `Params::pse` without a box or wall; products only.
    if let Some(t) = scene.free_space.and_then(|f| f.fast_tolerance()) {
        p.pse = Some(t);
    }
    p.matrix_free |= p.pse.is_some();
    p.near = scene.near_field.map(|n| n.kernel());
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The host's particle state is the heap crate's: one definition of the arrays.
    #[test]
    fn beads_are_the_heap_spheres() {
        use std::any::TypeId;
        let spheres = TypeId::of::<hydrorattle_heap::Spheres<f32>>();
        assert_eq!(TypeId::of::<Beads<f32>>(), spheres);
    }

    fn sphere(radius: f64) -> scene::Particle {
        scene::Particle {
            radius,
            density: 1.0,
            ..scene::Particle::default()
        }
    }

    #[test]
    fn values_valid_in_f64_are_checked_again_in_f32() {
        let ps = [sphere(1.0), sphere(1e-50)];
        assert!(beads::<f64>(&ps, 1.0).is_ok());
        let e = beads::<f32>(&ps, 1.0).unwrap_err();
        assert_eq!(e, ParticleError::BadRadius { particle: 1 });
        let e = beads::<f32>(&[sphere(1e300)], 1.0).unwrap_err();
        assert_eq!(e, ParticleError::NonFinite { particle: 0 });
    }

    #[test]
    fn bonds_are_validated_against_the_particle_count() {
        let b = |i, j| scene::Bond { i, j, length: 1.0 };
        assert_eq!(bonds::<f64>(&[b(0, 1)], 2).unwrap().len(), 1);
        let e = bonds::<f64>(&[b(0, 1), b(1, 0)], 2).unwrap_err();
        assert_eq!(e, BondError::Duplicate { bond: 1, other: 0 });
        let e = bonds::<f64>(&[b(0, 2)], 2).unwrap_err();
        assert_eq!(
            e,
            BondError::OutOfRange {
                bond: 0,
                particle: 2
            }
        );
    }
}
