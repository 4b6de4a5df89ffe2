//! The wave-space stage of every PSE product: spreading (forces, forces and torques,
//! or none for the noise already on the grid), the forward transforms, the kernel, the
//! inverse transforms and the interpolation, in pieces for the storage's [`Parallel`].

use core::convert::Infallible;

use super::{Cx, Pse, Source, Spheres, fft, jobs, spread, wave};
use crate::parallel::Parallel;
use crate::real::Real;

impl<T: Real> Pse<T> {
    /// `out += M^wave F` ([`Source::Force`]), `(out, spin) += M^wave (F, T)`
    /// ([`Source::Grand`]) or `out += (M^wave)^{1/2}`-distributed noise
    /// ([`Source::Noise`]), after the checks and the cell list (whose order the
    /// spreading follows). `rows` holds one vector per sphere, two for the grand product.
    pub(super) fn wave(
        &self,
        eta: T,
        s: Spheres<'_, T>,
        source: Source<'_, T>,
        (cx, rows, par): (&mut [Cx<T>], &mut [T::V3], &dyn Parallel),
        (out, spin): (&mut [T::V3], Option<&mut [T::V3]>),
    ) {
        match source {
            Source::Grand(..) => self.wave_of::<6>(eta, s, source, (cx, rows, par)),
            _ => self.wave_of::<3>(eta, s, source, (cx, rows, par)),
        }
        let w = if spin.is_some() { 2 } else { 1 };
        for (&i, r) in s.order.iter().zip(rows.chunks_exact(w)) {
            out[i] += r[0];
        }
        if let Some(spin) = spin {
            for (&i, r) in s.order.iter().zip(rows.chunks_exact(2)) {
                spin[i] += r[1];
            }
        }
    }

    /// [`Pse::wave`]'s grid work with `W` components per point (3, or 6 for the
    /// grand product's torques): the interpolated rows into `rows`, `W / 3` per sphere.
    fn wave_of<const W: usize>(
        &self,
        eta: T,
        s: Spheres<'_, T>,
        source: Source<'_, T>,
        (cx, rows, par): (&mut [Cx<T>], &mut [T::V3], &dyn Parallel),
    ) {
        let Spheres { pos, radius, order } = s;
        let [mx, my, mz] = self.grid.m;
        let points = mx * my * mz;
        let shape = fft::Grid3 {
            comps: W,
            ..self.grid
        };
        let each = shape.scratch_len();
        let (grid, rest) = cx.split_at_mut(W * points);
        let (scratch, rest) = rest.split_at_mut(jobs::JOBS * each);
        let (tw, table) = rest.split_at_mut(mx + my + mz);
        let (twx, rest) = tw.split_at_mut(mx);
        let (twy, twz) = rest.split_at_mut(my);
        fft::twiddles(mx, twx);
        fft::twiddles(my, twy);
        fft::twiddles(mz, twz);
        wave::tables(self, table);
        let tws = [&*twx, &*twy, &*twz];
        let slab = W * mx * my;
        // Spreading and the x, y transforms by slabs of planes (in parallel), the z
        // transforms and the kernel whole (their lines cross every slab).
        let sources = match source {
            Source::Force(force) => Some((force, None)),
            Source::Grand(force, torque) => Some((force, Some(torque))),
            // White noise of unit variance at every point, drawn by `noise_in`.
            Source::Noise => None,
        };
        if let Some(sources) = sources {
            let _ = jobs::pieces(par, (&mut *grid, mz, slab), jobs::none(), |z0, g, _| {
                g.fill([T::ZERO; 2]);
                let nz = g.len() / slab;
                let slab = spread::Slab { z0, nz };
                spread::spread::<T, W>(self, (pos, radius, order), sources, slab, g);
                Ok::<(), Infallible>(())
            });
        }
        let planes = |inverse: bool| {
            move |_: usize, g: &mut [Cx<T>], sc: &mut [Cx<T>]| {
                let part = fft::Grid3 {
                    m: [mx, my, g.len() / slab],
                    ..shape
                };
                fft::fft3(&part, g, sc, tws, inverse, 0..2);
                Ok::<(), Infallible>(())
            }
        };
        let _ = jobs::pieces(
            par,
            (&mut *grid, mz, slab),
            (&mut *scratch, each),
            planes(false),
        );
        fft::fft3(&shape, grid, &mut scratch[..each], tws, false, 2..3);
        match source {
            Source::Force(_) => wave::apply_kernel(self, eta, table, grid),
            Source::Grand(..) => wave::apply_kernel_grand(self, eta, table, grid),
            Source::Noise => wave::apply_sqrt_kernel(self, eta, table, grid),
        }
        fft::fft3(&shape, grid, &mut scratch[..each], tws, true, 2..3);
        let _ = jobs::pieces(
            par,
            (&mut *grid, mz, slab),
            (&mut *scratch, each),
            planes(true),
        );
        let grid = &*grid;
        let n = pos.len();
        let _ = jobs::pieces(par, (&mut *rows, n, W / 3), jobs::none(), |a, r, _| {
            let k = a..a + r.len() / (W / 3);
            spread::interpolate::<T, W>(self, (pos, radius, &order[k]), grid, r);
            Ok::<(), Infallible>(())
        });
    }
}
