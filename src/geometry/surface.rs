//! The hard surfaces of a place ([`Surfaces`], asked by
//! [`Place::surfaces`](super::Place::surfaces)): the planes a sphere may not cross,
//! which the acceptance checks, the workspace holds a link a sphere for, and the
//! contacts hold. Each geometry answers in its own module (the wall: its plane; free
//! space and the box: none).

use crate::real::Real;

/// The most hard surfaces a place has: two, the planes of a slit between two walls.
pub const MAX_SURFACES: usize = 2;

/// The plane `z = height` that the spheres stay on one side of, a radius clear: above
/// it (a floor, normal `+z`: the wall) or below it (a ceiling, normal `-z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface<T> {
    /// The plane's height.
    pub height: T,
    /// Whether the spheres are above the plane (its normal `+z`), not below it.
    pub above: bool,
}

impl<T: Real> Surface<T> {
    /// The floor `z = height`: the spheres above it.
    #[inline(always)]
    pub const fn floor(height: T) -> Self {
        Self {
            height,
            above: true,
        }
    }

    /// The ceiling `z = height`: the spheres below it.
    #[inline(always)]
    pub const fn ceiling(height: T) -> Self {
        Self {
            height,
            above: false,
        }
    }

    /// How far a centre at height `z` is from the plane, on the spheres' side
    /// (negative past it).
    #[inline(always)]
    pub fn gap(self, z: T) -> T {
        match self.above {
            true => z - self.height,
            false => self.height - z,
        }
    }

    /// The first sphere whose centre is nearer the plane than `a_i (1 - 2 tol)`, less
    /// the rounding of the numbers compared (4 epsilons of `|z| + |height| + a_i`): far
    /// from the origin a sphere put or held at contact is off by an ulp of its
    /// coordinates, which can exceed `2 tol a_i`. A centre that is not strictly on the
    /// spheres' side in the step's precision (a gap `<= 0`: the coordinates' spacing
    /// there exceeds the radius, f32 far from the origin) has crossed whatever that
    /// rounding: the wall's mobility has no value there (`mobility::wall`), and a scene
    /// checked with this test at parse time is not refused at its first step by that one.
    pub fn first_crossed(self, pos: &[T::V3], radius: &[T], tol: T) -> Option<usize> {
        let reach = T::ONE - tol * T::TWO;
        let ulps = T::EPSILON * T::from_f64(4.0);
        pos.iter().zip(radius).position(|(&r, &a)| {
            let z = T::xyz(r)[2];
            let gap = self.gap(z);
            let rounding = (z.abs() + self.height.abs() + a) * ulps;
            !(gap > T::ZERO && gap + rounding >= a * reach)
        })
    }
}

/// A place's hard surfaces: none, or up to [`MAX_SURFACES`] planes, in order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surfaces<T> {
    planes: [Option<Surface<T>>; MAX_SURFACES],
}

impl<T: Real> Surfaces<T> {
    /// No hard surface (free space, the box).
    pub const NONE: Self = Self {
        planes: [None, None],
    };

    /// The one plane `s` (the wall's).
    #[inline(always)]
    pub const fn one(s: Surface<T>) -> Self {
        Self {
            planes: [Some(s), None],
        }
    }

    /// The two planes `a` and `b` (a slit's).
    #[inline(always)]
    pub const fn two(a: Surface<T>, b: Surface<T>) -> Self {
        Self {
            planes: [Some(a), Some(b)],
        }
    }

    /// Whether there is none.
    #[inline(always)]
    pub const fn is_empty(self) -> bool {
        self.planes[0].is_none()
    }

    /// How many there are.
    #[inline(always)]
    pub const fn len(self) -> usize {
        match self.planes {
            [None, _] => 0,
            [Some(_), None] => 1,
            [Some(_), Some(_)] => 2,
        }
    }

    /// Each plane, in order.
    #[inline(always)]
    pub fn iter(self) -> impl Iterator<Item = Surface<T>> {
        self.planes.into_iter().flatten()
    }

    /// The height of the first floor (a plane the spheres stay above): what the
    /// contacts' wall links hold (they run in its frame, [`Bond::wall`](crate::Bond::wall)).
    #[inline(always)]
    pub const fn floor(self) -> Option<T> {
        self.first(true)
    }

    /// The height of the first ceiling (a plane the spheres stay below: a slit's
    /// upper one), which the contacts' ceiling links hold
    /// ([`Bond::ceiling`](crate::Bond::ceiling)).
    #[inline(always)]
    pub const fn ceiling(self) -> Option<T> {
        self.first(false)
    }

    /// The height of the first plane with the spheres `above` it (or below).
    #[inline(always)]
    const fn first(self, above: bool) -> Option<T> {
        match self.planes {
            [Some(s), _] if s.above == above => Some(s.height),
            [_, Some(s)] if s.above == above => Some(s.height),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// A ceiling is a floor seen upside down: a sphere crosses the ceiling `z = h` where
    /// its mirror image `-z` crosses the floor `z = -h`, and the gaps are the distances
    /// from the plane, signed by the side.
    #[test]
    fn a_ceiling_mirrors_a_floor() {
        let (h, a, tol) = (1.5, 0.5, 1e-6);
        for z in [-3.0, 0.0, 1.0, 1.9, 2.0 - 1e-9, 2.0, 2.1, 4.0] {
            let up = [DVec3::new(0.3, -0.2, z)];
            let down = [DVec3::new(0.3, -0.2, -z)];
            let floor = Surface::floor(h).first_crossed(&up, &[a], tol);
            let ceiling = Surface::ceiling(-h).first_crossed(&down, &[a], tol);
            assert_eq!(floor, ceiling, "z = {z}");
            // Closed form: crossed unless the centre is a radius clear (within tolerance).
            assert_eq!(
                floor.is_some(),
                z - h < a * (1.0 - 2.0 * tol) - 1e-12,
                "z = {z}"
            );
            assert_eq!(Surface::floor(h).gap(z), z - h);
            assert_eq!(Surface::ceiling(-h).gap(-z), z - h);
        }
    }

    /// A place's surfaces: counted in order, and the floor is what the contacts hold.
    #[test]
    fn surfaces_count_and_the_floor() {
        let (f, c) = (Surface::floor(0.5), Surface::ceiling(9.0));
        let cases: [(Surfaces<f64>, usize, Option<f64>); 4] = [
            (Surfaces::NONE, 0, None),
            (Surfaces::one(f), 1, Some(0.5)),
            (Surfaces::one(c), 1, None),
            (Surfaces::two(f, c), 2, Some(0.5)),
        ];
        for (s, n, floor) in cases {
            assert_eq!((s.len(), s.is_empty(), s.floor()), (n, n == 0, floor));
            assert_eq!(s.iter().count(), n);
        }
        let mut both = Surfaces::two(f, c).iter();
        assert_eq!(
            (both.next(), both.next(), both.next()),
            (Some(f), Some(c), None)
        );
    }
}
