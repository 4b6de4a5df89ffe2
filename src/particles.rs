//! Fixed-capacity set of rigid spheres: the dynamic state and the per-particle data.

use crate::fault::ParticleError;
use crate::noise::Noise;
use crate::real::Real;

/// One sphere, as handed to [`ParticleSet::push`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle<T: Real> {
    /// Centre.
    pub position: T::V3,
    /// Translational velocity.
    pub velocity: T::V3,
    /// Radius (> 0).
    pub radius: T,
    /// Material density (>= 0); mass is `4/3 pi a^3 density`.
    pub density: T,
}

impl<T: Real> Particle<T> {
    /// A sphere at rest.
    pub fn new(position: T::V3, radius: T, density: T) -> Self {
        Self {
            position,
            velocity: T::V3_ZERO,
            radius,
            density,
        }
    }
}

/// Up to `N` spheres. Storage is inline, so a set can live in a `static` or on the stack.
///
/// Fields are public slices-of-arrays for the integrators; only the first
/// [`len`](Self::len) entries are meaningful.
#[derive(Clone, Debug)]
pub struct ParticleSet<T: Real, const N: usize> {
    len: usize,
    /// Centres.
    pub pos: [T::V3; N],
    /// Translational velocities.
    pub vel: [T::V3; N],
    /// Angular velocities (written by methods that resolve or report rotation).
    pub omega: [T::V3; N],
    /// Radii.
    pub radius: [T; N],
    /// Material densities.
    pub density: [T; N],
    /// Simulated time.
    pub time: T,
    /// The thermal-noise generator a step at temperature draws from ([`State::noise`]);
    /// `None` (the default) for deterministic runs.
    pub noise: Option<Noise>,
}

impl<T: Real, const N: usize> Default for ParticleSet<T, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize> ParticleSet<T, N> {
    /// An empty set.
    pub const fn new() -> Self {
        const { assert!(N > 0, "capacity N must be positive") };
        Self {
            len: 0,
            pos: [T::V3_ZERO; N],
            vel: [T::V3_ZERO; N],
            omega: [T::V3_ZERO; N],
            radius: [T::ZERO; N],
            density: [T::ZERO; N],
            time: T::ZERO,
            noise: None,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Adds a particle after checking it on its own (finite, radius > 0, density >= 0).
    /// Pair checks (nesting, overlap) are [`validate`](Self::validate)'s job.
    ///
    /// Hands the particle back with the reason when it is rejected or the set is full.
    pub fn push(&mut self, p: Particle<T>) -> Result<usize, (Particle<T>, ParticleError)> {
        let i = self.len;
        if i == N {
            return Err((p, ParticleError::Full));
        }
        if let Err(e) = check_one(i, &p) {
            return Err((p, e));
        }
        self.pos[i] = p.position;
        self.vel[i] = p.velocity;
        self.omega[i] = T::V3_ZERO;
        self.radius[i] = p.radius;
        self.density[i] = p.density;
        self.len += 1;
        Ok(i)
    }

    /// Builds a set from a slice, validating everything (overlap allowed or not).
    pub fn from_slice(ps: &[Particle<T>], allow_overlap: bool) -> Result<Self, ParticleError> {
        let mut set = Self::new();
        for p in ps {
            set.push(*p).map_err(|(_, e)| e)?;
        }
        set.validate(allow_overlap)?;
        Ok(set)
    }

    /// Mass of particle `i`: `4/3 pi a^3 rho`.
    pub fn mass(&self, i: usize) -> T {
        sphere_volume(self.radius[i]) * self.density[i]
    }

    /// Checks every particle and every pair. Nested spheres are always an error;
    /// overlapping ones only when `allow_overlap` is false.
    pub fn validate(&self, allow_overlap: bool) -> Result<(), ParticleError> {
        let n = self.len;
        for i in 0..n {
            let p = Particle {
                position: self.pos[i],
                velocity: self.vel[i],
                radius: self.radius[i],
                density: self.density[i],
            };
            check_one(i, &p)?;
            if !T::v3_is_finite(self.omega[i]) {
                return Err(ParticleError::NonFinite { particle: i });
            }
        }
        check_pairs(&self.pos[..n], &self.radius[..n], allow_overlap)
    }
}

/// A mutable view of `n` particles' state in caller-owned slices (all of length `n`):
/// what [`step_slices`](crate::integrate::step_slices) advances. Hosts keep the arrays
/// anywhere (vectors of any length); [`ParticleSet::state`] gives this view of a set.
#[derive(Debug)]
pub struct State<'a, T: Real> {
    /// Centres.
    pub pos: &'a mut [T::V3],
    /// Translational velocities.
    pub vel: &'a mut [T::V3],
    /// Angular velocities.
    pub omega: &'a mut [T::V3],
    /// Radii.
    pub radius: &'a [T],
    /// Material densities.
    pub density: &'a [T],
    /// Simulated time.
    pub time: &'a mut T,
    /// The generator of the thermal noise ([`Params::brownian`](crate::Params::brownian)
    /// with `kT > 0`), part of the state a step carries: the step draws from a copy and
    /// writes it back only when it succeeds, so a refused step leaves it as it was. A
    /// step at `kT > 0` without one is refused; at `kT = 0` it is not touched.
    pub noise: Option<&'a mut Noise>,
}

impl<T: Real> State<'_, T> {
    /// Number of particles (the length of `pos`).
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// `true` when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }
}

impl<T: Real, const N: usize> ParticleSet<T, N> {
    /// The state of the first [`len`](Self::len) particles as slices.
    pub fn state(&mut self) -> State<'_, T> {
        let n = self.len;
        State {
            pos: &mut self.pos[..n],
            vel: &mut self.vel[..n],
            omega: &mut self.omega[..n],
            radius: &self.radius[..n],
            density: &self.density[..n],
            time: &mut self.time,
            noise: self.noise.as_mut(),
        }
    }
}

/// Volume of a sphere of radius `a`.
pub fn sphere_volume<T: Real>(a: T) -> T {
    T::from_f64(4.0 / 3.0) * T::PI * a * a * a
}

/// Checks particle `i` on its own: finite values, radius > 0, density >= 0 (the checks
/// [`ParticleSet::push`] makes; pair checks are [`check_pairs`]).
pub fn check_one<T: Real>(i: usize, p: &Particle<T>) -> Result<(), ParticleError> {
    let finite = T::v3_is_finite(p.position)
        && T::v3_is_finite(p.velocity)
        && p.radius.is_finite()
        && p.density.is_finite();
    if !finite {
        return Err(ParticleError::NonFinite { particle: i });
    }
    if !(p.radius >= T::MIN_POSITIVE) {
        return Err(ParticleError::BadRadius { particle: i });
    }
    if p.density < T::ZERO {
        return Err(ParticleError::BadDensity { particle: i });
    }
    Ok(())
}

/// Pair checks on positions and radii: nesting always fails, overlap when not allowed.
/// Fixed order (i ascending, then j), so the reported pair is deterministic. Visits
/// every pair; [`check_pairs_in`](crate::cell_list::check_pairs_in) gives the same
/// answer over a cell list.
pub fn check_pairs<T: Real>(
    pos: &[T::V3],
    radius: &[T],
    allow_overlap: bool,
) -> Result<(), ParticleError> {
    crate::cell_list::check_pairs_in(pos, radius, allow_overlap, &mut [])
}
