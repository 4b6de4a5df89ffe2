//! [`Params::map`]: the same parameters in another [`Real`], field by field.
//!
//! Why: a host that runs the kernel in a type of its own (several systems side by side
//! in the lanes of one value, `hydrorattle-parallel`'s `batch`) needs the parameters in
//! that type, built from the `f64` ones it was given, without restating every field
//! (a copy that would fall behind when a field is added). The order in which the real
//! fields are visited is fixed and documented, so a caller may also zip several
//! parameter sets into one (record each set's values, replay them lane by lane).

use super::{Brownian, Params, Wall};
use crate::cell::{Periodic, PeriodicError};
use crate::constraints::Solver;
use crate::noise::lanczos::Lanczos;
use crate::real::Real;

impl<T: Real> Params<T> {
    /// These parameters with every real field passed through `f` and every other field
    /// (method, flags, counts, options' presence, [`Params::pse`]'s `f64` tolerance)
    /// copied. The real fields are visited in this order, vectors component by
    /// component (`x`, `y`, `z`), an absent option skipped: `dt`, `viscosity`,
    /// `fluid_density`, `gravity`, `flow_velocity`, `vorticity`, the solver's
    /// tolerance, `spring_stiffness`, `fene`, the Brownian temperature, the Lanczos
    /// tolerance, the wall's height, the box's three edges.
    ///
    /// `p.map(|x| U::from_f64(x.to_f64()))` converts the precision (rounding once
    /// per field, as building the parameters in `U` from the same numbers would).
    ///
    /// # Errors
    /// [`PeriodicError::BadEdge`] when `f` maps an edge of the box to a value that is
    /// not positive and finite (the box checks its edges once, when it is built).
    pub fn map<U: Real>(&self, mut f: impl FnMut(T) -> U) -> Result<Params<U>, PeriodicError> {
        fn v3<T: Real, U: Real>(f: &mut impl FnMut(T) -> U, v: T::V3) -> U::V3 {
            let [x, y, z] = T::xyz(v);
            let x = f(x);
            let y = f(y);
            U::v3(x, y, f(z))
        }
        let dt = f(self.dt);
        let viscosity = f(self.viscosity);
        let fluid_density = f(self.fluid_density);
        let gravity = v3(&mut f, self.gravity);
        let flow_velocity = v3(&mut f, self.flow_velocity);
        let vorticity = v3(&mut f, self.vorticity);
        let solver = Solver {
            kind: self.solver.kind,
            tolerance: f(self.solver.tolerance),
            max_iterations: self.solver.max_iterations,
        };
        let spring_stiffness = f(self.spring_stiffness);
        let fene = self.fene.map(&mut f);
        let brownian = self.brownian.map(|b| Brownian {
            temperature: f(b.temperature),
            drift: b.drift,
        });
        let lanczos = Lanczos {
            tolerance: f(self.lanczos.tolerance),
            max_iterations: self.lanczos.max_iterations,
        };
        let wall = self.wall.map(|w| Wall::new(f(w.height)));
        let periodic = match self.periodic {
            Some(c) => {
                let [x, y, z] = c.size();
                let x = f(x);
                let y = f(y);
                Some(Periodic::new([x, y, f(z)])?)
            }
            None => None,
        };
        Ok(Params {
            dt,
            viscosity,
            fluid_density,
            gravity,
            flow_velocity,
            vorticity,
            hydro: self.hydro,
            method: self.method,
            rotation: self.rotation,
            matrix_free: self.matrix_free,
            solver,
            allow_overlap: self.allow_overlap,
            spring_stiffness,
            fene,
            stability_guard: self.stability_guard,
            brownian,
            noise_sqrt: self.noise_sqrt,
            lanczos,
            contacts: self.contacts,
            wall,
            periodic,
            compact_products: self.compact_products,
            resolve_tensions: self.resolve_tensions,
            pse: self.pse,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::{Contacts, Drift, Method, NoiseSqrt};

    /// Every field set away from its default, so that a field `map` dropped or crossed
    /// would show; in any precision, each real built from its `f64` literal.
    fn odd<T: Real>() -> Result<Params<T>, PeriodicError> {
        let r = T::from_f64;
        let mut p = Params::new(r(0.125));
        p.viscosity = r(2.5);
        p.fluid_density = r(0.75);
        p.gravity = T::v3_from([0.1, -0.2, -9.75]);
        p.flow_velocity = T::v3_from([1.0, 2.0, 3.0]);
        p.vorticity = T::v3_from([-4.0, 5.0, -6.0]);
        p.hydro = crate::Hydro::Oseen;
        p.method = Method::Springs;
        p.rotation = true;
        p.matrix_free = true;
        p.solver.tolerance = r(1e-9);
        p.solver.max_iterations = 7;
        p.allow_overlap = true;
        p.spring_stiffness = r(321.0);
        p.fene = Some(r(3.5));
        p.stability_guard = true;
        p.brownian = Some(Brownian {
            temperature: r(0.01),
            drift: Drift::Uncorrected,
        });
        p.noise_sqrt = NoiseSqrt::Lanczos;
        p.lanczos.tolerance = r(1e-5);
        p.lanczos.max_iterations = 9;
        p.contacts = Some(Contacts::new(11));
        p.wall = Some(Wall::new(r(-7.0)));
        p.periodic = Some(Periodic::new([10.0, 20.0, 30.0].map(r))?);
        p.compact_products = true;
        p.resolve_tensions = true;
        p.pse = Some(1e-4);
        Ok(p)
    }

    /// The identity gives the parameters back; every real field is visited once, in
    /// the documented order (the values written above, read off in that order).
    #[test]
    fn identity_and_order() -> Result<(), PeriodicError> {
        let p = odd::<f64>()?;
        let mut seen = [0.0; 21];
        let mut k = 0;
        let q = p.map(|x: f64| {
            seen[k] = x;
            k += 1;
            x
        })?;
        assert_eq!(q, p);
        let want = [
            0.125, 2.5, 0.75, 0.1, -0.2, -9.75, 1.0, 2.0, 3.0, -4.0, 5.0, -6.0, 1e-9, 321.0, 3.5,
            0.01, 1e-5, -7.0, 10.0, 20.0, 30.0,
        ];
        assert_eq!((k, seen), (want.len(), want));
        Ok(())
    }

    /// To `f32`: each real rounded once, the rest copied (against the same parameters
    /// built in `f32` field by field).
    #[test]
    fn cast_to_f32() -> Result<(), PeriodicError> {
        assert_eq!(odd::<f64>()?.map(|x: f64| x as f32)?, odd::<f32>()?);
        Ok(())
    }

    /// An edge mapped out of range is the box's own error, with its axis.
    #[test]
    fn bad_edge_is_refused() -> Result<(), PeriodicError> {
        let r = odd::<f64>()?.map(|x: f64| if x == 20.0 { -1.0 } else { x });
        assert_eq!(r, Err(PeriodicError::BadEdge { axis: 1 }));
        Ok(())
    }
}
