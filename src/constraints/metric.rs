//! How a unit multiplier on bond `l` displaces the beads: `D_l(p)`.
//!
//! Every metric pushes along the bond vectors `g_l` of the step's start (the
//! SHAKE/RATTLE convention). The mass metric moves only the bond's two beads; the
//! hydrodynamic metrics move every bead, but none of them is ever stored as a dense
//! `beads x bonds` array except [`Metric::Dense`], which the small dense solve of the
//! implicit-drag integrator uses.
//!
//! A wall link ([`Bond::wall`]) pushes on its sphere alone: its `j` term is absent
//! (`D_l(p) = scale mu_pi g_l`), and the change of its relative vector is the normal
//! component of its sphere's displacement ([`Bond::relative`]). A pin row
//! ([`Bond::pin`]) is the same along its axis.

use crate::bonds::Bond;
use crate::linalg::{self, Block, Mob, tri, with_blocks};
use crate::mobility::{Hydro, tt_block_at, wall};
#[cfg(feature = "periodic")]
use crate::mobility::{periodic, sums::BoxSums};
use crate::parallel::Parallel;
use crate::real::Real;

/// How a unit multiplier on bond `l` displaces bead `p`.
#[derive(Clone, Copy, Debug)]
pub enum Metric<'a, T: Real> {
    /// Inverse-mass metric (the paper's eqs. 3-4): `+scale g_l / m_i` on `i`,
    /// `-scale g_l / m_j` on `j`, zero elsewhere.
    Mass {
        /// `1 / m` per bead.
        inv_mass: &'a [T],
        /// Constraint gradients `g_l = r_i - r_j`, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt^2 / 2` for positions).
        scale: T,
    },
    /// Hydrodynamic metric from the packed translational mobility:
    /// `D_l(p) = (mu_pi - mu_pj) (scale g_l)`, read block by block where it is used.
    Mobility {
        /// Packed `mu_tt` (`tri(n)` blocks, symmetric in free space).
        mu: Mob<'a, T>,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt` for positions).
        scale: T,
        /// How its products run ([`crate::parallel::product`]).
        par: &'a dyn Parallel,
        /// The compact `f32` copy of `mu` ([`crate::noise::reduced`]) when the
        /// products of [`Metric::apply_all`] read it (mixed precision,
        /// [`Params::compact_products`](crate::Params::compact_products)); `None`:
        /// they read `mu`. Everything else reads `mu`.
        compact: Option<&'a [T::M3]>,
    },
    /// The same hydrodynamic metric without a stored mobility: each pair block is
    /// evaluated where it is used (matrix-free; bit-identical to [`Metric::Mobility`]).
    /// The positions must have passed a product at these positions ([`tt_product`](crate::mobility::tt_product)),
    /// which refuses nested spheres.
    Free {
        /// Hydrodynamic level.
        level: Hydro,
        /// Viscosity.
        eta: T,
        /// Bead centres.
        pos: &'a [T::V3],
        /// Bead radii.
        radius: &'a [T],
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
        /// Overall factor (`dt` for positions).
        scale: T,
        /// The wall's height when there is one ([`wall`]).
        wall: Option<T>,
        /// The step's periodic sums when it runs in a box whose images interact
        /// (derived once per step, not per block: `integrate/periodic.rs`): Ewald, or
        /// PSE, which has products only (its `D_l(p)` entries are zero: the step
        /// refuses the solvers that read them).
        #[cfg(feature = "periodic")]
        ewald: Option<BoxSums<'a, T>>,
        /// How its free-space products run ([`crate::parallel::free_product`], the bits
        /// of the stored product on any number of threads).
        par: &'a dyn Parallel,
    },
    /// Precomputed displacements `disp[l * beads + p]` (`bonds x beads`, bond-major: a
    /// multiplier's moves of all beads are contiguous, so the table is written in order
    /// and an update of all multipliers keeps a few beads' running sums in registers,
    /// adjacent beads' coordinates side by side, [`Metric::apply_each`]).
    Dense {
        /// Displacements, bond-major.
        disp: &'a [T::V3],
        /// Beads.
        n: usize,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
    },
    /// Implicit-drag metric `D_l = dt Q g_l`, `Q = (R + M/dt)^-1 = dt S^-1 K^-1 S mu`
    /// with `K = dt I + S mu S` factorised (the stable inertial integrator). Only its
    /// action on a whole multiplier vector is available: one mobility product and one
    /// Cholesky solve. Solved by the Krylov solver only.
    Drag {
        /// Packed mobility (`tri(m)` blocks, `m = n` or `2n` with rotation).
        mu: &'a [T::M3],
        /// Cholesky factor of `K`, packed.
        fac: &'a [T::M3],
        /// `S`: `sqrt(m)` per bead, then `sqrt(I)` per bead with rotation (length `m`).
        sq: &'a [T],
        /// Time step.
        dt: T,
        /// Constraint gradients, one per bond.
        grad: &'a [T::V3],
    },
}

/// Block `(q, p)` of a packed symmetric matrix, `mu_pq^T`: read as it is stored for
/// `q > p`, transposed for `q <= p` (exact; the free-space blocks are symmetric, so
/// this is their stored block bit for bit, while a wall's pair blocks are not,
/// [`wall`]).
#[inline(always)]
fn sym_block<T: Real, B: Block<T>>(mu: &[B], p: usize, q: usize) -> T::M3 {
    if q <= p {
        // Symmetric blocks (and every block without the `wall` feature): no transpose
        // needed.
        let b = mu[tri(p) + q].full();
        if cfg!(feature = "wall") && B::SCALARS == 9 {
            T::transpose(b)
        } else {
            b
        }
    } else {
        mu[tri(q) + p].full()
    }
}

/// `(a - c)^T g`: `(A_pi - A_pj) g` from the blocks [`sym_block`] gives (the wall's
/// pair blocks are not symmetric). For symmetric blocks these are the bits of
/// `(a - c) * g` (the same products summed in glam's order, the entries equal to their
/// transposes).
/// `sym` says the blocks are known symmetric (no wall in this step): then, as without
/// the `wall` feature, only their lower triangles are read.
#[inline(always)]
fn sym_diff_mul<T: Real>(a: T::M3, c: T::M3, g: T::V3, sym: bool) -> T::V3 {
    let d = |r, col| T::m3_get(a, r, col) - T::m3_get(c, r, col);
    let [x, y, z] = T::xyz(g);
    if !cfg!(feature = "wall") || sym {
        // Symmetric blocks only: the lower triangles suffice (12 loads and 6
        // subtractions instead of 18 and 9), the same bits (M4 firmware's hot loop).
        let (d00, d10, d20) = (d(0, 0), d(1, 0), d(2, 0));
        let (d11, d21, d22) = (d(1, 1), d(2, 1), d(2, 2));
        return T::v3(
            d00 * x + d10 * y + d20 * z,
            d10 * x + d11 * y + d21 * z,
            d20 * x + d21 * y + d22 * z,
        );
    }
    T::v3(
        d(0, 0) * x + d(1, 0) * y + d(2, 0) * z,
        d(0, 1) * x + d(1, 1) * y + d(2, 1) * z,
        d(0, 2) * x + d(1, 2) * y + d(2, 2) * z,
    )
}

/// `y <- S^-1 dt K^-1 S y` with `K = dt I + S mu S` factorised in `fac`.
pub(crate) fn apply_drag<T: Real>(fac: &[T::M3], sq: &[T], dt: T, y: &mut [T::V3]) {
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= q;
    }
    linalg::cholesky_solve::<T>(fac, sq.len(), y);
    for (v, &q) in y.iter_mut().zip(sq) {
        *v *= dt / q;
    }
}

impl<T: Real> Metric<'_, T> {
    /// The bond vector multiplier `l` pushes along.
    #[inline]
    pub fn grad(&self, l: usize) -> T::V3 {
        match *self {
            Metric::Mass { grad, .. }
            | Metric::Mobility { grad, .. }
            | Metric::Free { grad, .. }
            | Metric::Dense { grad, .. }
            | Metric::Drag { grad, .. } => grad[l],
        }
    }

    /// Displacement of bead `p` per unit multiplier on bond `l`. Exact for every metric
    /// but [`Metric::Drag`], where it is the preconditioner's local model
    /// `Q_pq ~ sqrt(c_p c_q) mu_pq`, `c_p = 1 / (1 + m_p mu_pp / dt)`: exact for a lone
    /// bead, `mu` as the masses vanish and `dt / m` as they grow.
    #[inline(always)]
    pub fn at(&self, bonds: &[Bond<T>], l: usize, p: usize) -> T::V3 {
        let b = bonds[l];
        match *self {
            Metric::Mass {
                inv_mass,
                grad,
                scale,
            } => {
                if p == b.i {
                    grad[l] * (scale * inv_mass[p])
                } else if p == b.j {
                    grad[l] * (-scale * inv_mass[p])
                } else {
                    T::V3_ZERO
                }
            }
            Metric::Dense { disp, n, .. } => disp[l * n + p],
            _ => self.at_far(bonds, l, p),
        }
    }

    /// [`Metric::at`] for the metrics that compute it (mobility blocks, matrix-free
    /// blocks, the drag model). Called, not inlined, on 32-bit Arm: `at` is inlined at
    /// every call site (the Jacobian rows, the moves) and these arms would be copied
    /// into each (~2 kB of firmware flash); the firmware's dense solves read
    /// [`Metric::Dense`] or [`Metric::Mass`], which stay inline.
    #[cfg_attr(target_arch = "arm", inline(never))]
    #[cfg_attr(not(target_arch = "arm"), inline(always))]
    fn at_far(&self, bonds: &[Bond<T>], l: usize, p: usize) -> T::V3 {
        let b = bonds[l];
        match *self {
            // Read inline by `at`, which never calls this for them.
            Metric::Mass { .. } | Metric::Dense { .. } => T::V3_ZERO,
            Metric::Mobility {
                mu, grad, scale, ..
            } => {
                let g = grad[l] * scale;
                with_blocks!(mu, mu => {
                    let mu_pj = match b.one_sphere() {
                        true => T::M3_ZERO,
                        false => sym_block::<T, _>(mu, p, b.j),
                    };
                    sym_diff_mul::<T>(sym_block::<T, _>(mu, p, b.i), mu_pj, g, false)
                })
            }
            Metric::Free {
                level,
                eta,
                pos,
                radius,
                grad,
                scale,
                wall,
                #[cfg(feature = "periodic")]
                ewald,
                ..
            } => {
                #[cfg(feature = "periodic")]
                if let Some(sums) = ewald {
                    return match sums.ewald() {
                        Some(ew) => periodic_at(ew, eta, pos, radius, b, grad[l] * scale, p),
                        None => T::V3_ZERO,
                    };
                }
                // Nested pairs were refused by the product at these positions. The block
                // (q, p), as `sym_block` reads it.
                let block = |q| match wall {
                    Some(h) if cfg!(feature = "wall") => {
                        wall::tt_block_at(level, eta, h, pos, radius, q, p).ok()
                    }
                    _ => tt_block_at(level, eta, pos, radius, p, q),
                };
                let block = |q| block(q).unwrap_or(T::M3_ZERO);
                let mu_pj = if b.one_sphere() {
                    T::M3_ZERO
                } else {
                    block(b.j)
                };
                sym_diff_mul::<T>(block(b.i), mu_pj, grad[l] * scale, false)
            }
            Metric::Drag {
                mu, sq, dt, grad, ..
            } => {
                let c = |q: usize| {
                    let self_mu = T::m3_get(mu[tri(q) + q], 0, 0);
                    T::ONE / (T::ONE + sq[q] * sq[q] * self_mu / dt)
                };
                let cp = c(p);
                let g = grad[l] * dt;
                let q_pi = linalg::sym_get::<T>(mu, p, b.i) * (cp * c(b.i)).sqrt();
                let q_pj = linalg::sym_get::<T>(mu, p, b.j) * (cp * c(b.j)).sqrt();
                q_pi * g - q_pj * g
            }
        }
    }

    /// Change of bond `k`'s vector per unit multiplier on bond `l`.
    #[inline(always)]
    pub fn relative(&self, bonds: &[Bond<T>], k: usize, l: usize) -> T::V3 {
        let b = bonds[k];
        if b.one_sphere() {
            return crate::bonds::component::<T>(self.at(bonds, l, b.i), b.axis());
        }
        self.at(bonds, l, b.i) - self.at(bonds, l, b.j)
    }

    /// `row[l - first] = dir . (D_l(i_k) - D_l(j_k))` for `l` in `first..first + row.len()`:
    /// a row of the constraint Jacobian. The metric is matched once per row, not per
    /// entry (this is the dense solve's inner loop).
    pub fn jacobian_row(
        &self,
        bonds: &[Bond<T>],
        k: usize,
        dir: T::V3,
        first: usize,
        row: &mut [T],
    ) {
        let b = bonds[k];
        match *self {
            Metric::Dense { disp, n, .. } => {
                let rows = disp[first * n..].chunks_exact(n);
                if b.one_sphere() {
                    // A wall link moves its sphere alone.
                    for (r, d) in row.iter_mut().zip(rows) {
                        *r = T::dot(dir, d[b.i]);
                    }
                } else {
                    for (r, d) in row.iter_mut().zip(rows) {
                        *r = T::dot(dir, d[b.i] - d[b.j]);
                    }
                }
            }
            _ => {
                for (l, r) in (first..).zip(row.iter_mut()) {
                    *r = T::dot(dir, self.relative(bonds, k, l));
                }
            }
        }
    }

    /// `x += c D_l` (one bond; the sweep and the dense Newton update).
    pub fn apply_one(&self, bonds: &[Bond<T>], l: usize, c: T, x: &mut [T::V3]) {
        match *self {
            Metric::Mass { .. } => {
                let b = bonds[l];
                x[b.i] += self.at(bonds, l, b.i) * c;
                if !b.one_sphere() {
                    x[b.j] += self.at(bonds, l, b.j) * c;
                }
            }
            Metric::Dense { disp, n, .. } => {
                for (xp, &d) in x.iter_mut().zip(&disp[l * n..(l + 1) * n]) {
                    *xp += d * c;
                }
            }
            Metric::Mobility { .. } | Metric::Free { .. } | Metric::Drag { .. } => {
                for p in 0..x.len() {
                    x[p] += self.at(bonds, l, p) * c;
                }
            }
        }
    }

    /// `x += sum_l c_l D_l`, the multipliers' moves added bond after bond (the bits of
    /// [`Metric::apply_one`] for `l = 0, 1, ...`; the dense Newton update). The table
    /// is read four beads at a time: their twelve running sums stay in registers and
    /// adjacent beads' coordinates are adjacent in memory, so the compiler pairs them
    /// into packed SIMD operations (no reordering: the same bits).
    pub fn apply_each(&self, bonds: &[Bond<T>], c: &[T], x: &mut [T::V3]) {
        match *self {
            Metric::Dense { disp, n, .. } => {
                const W: usize = 4;
                let rows = || disp.chunks_exact(n).zip(c);
                let mut chunks = x.chunks_exact_mut(W);
                for (k, xs) in (&mut chunks).enumerate() {
                    let mut acc = [xs[0], xs[1], xs[2], xs[3]];
                    for (row, &cl) in rows() {
                        let d = &row[k * W..k * W + W];
                        for (a, &dp) in acc.iter_mut().zip(d) {
                            *a += dp * cl;
                        }
                    }
                    xs.copy_from_slice(&acc);
                }
                let first = x.len() - x.len() % W;
                for (p, xp) in x.iter_mut().enumerate().skip(first) {
                    let mut acc = *xp;
                    for (row, &cl) in rows() {
                        acc += row[p] * cl;
                    }
                    *xp = acc;
                }
            }
            _ => {
                for (l, &cl) in c.iter().enumerate().take(bonds.len()) {
                    self.apply_one(bonds, l, cl, x);
                }
            }
        }
    }

    /// `out = sum_l c_l D_l` over all bonds at once (the Krylov solver's product):
    /// `G^T c`, then one mobility product (and one drag solve). `tmp` holds at least
    /// `2m` vectors (`m` block rows of the mobility), and for [`Metric::Mobility`] and
    /// [`Metric::Free`] `n` and the product's
    /// [`band_scratch`](crate::parallel::band_scratch).
    pub fn apply_all(&self, bonds: &[Bond<T>], c: &[T], out: &mut [T::V3], tmp: &mut [T::V3]) {
        let n = out.len();
        match *self {
            Metric::Mass {
                inv_mass,
                grad,
                scale,
            } => {
                out.fill(T::V3_ZERO);
                for (l, b) in bonds.iter().enumerate() {
                    let g = grad[l] * (c[l] * scale);
                    out[b.i] += g * inv_mass[b.i];
                    if !b.one_sphere() {
                        out[b.j] -= g * inv_mass[b.j];
                    }
                }
            }
            Metric::Dense { .. } => {
                out.fill(T::V3_ZERO);
                self.apply_each(bonds, c, out);
            }
            Metric::Mobility {
                mu,
                grad,
                scale,
                par,
                compact,
            } => {
                let (f, bands) = tmp.split_at_mut(n);
                spread(bonds, grad, c, scale, f);
                match compact {
                    Some(copy) => crate::noise::reduced::apply::<T>(par, copy, n, f, out, bands),
                    None => {
                        with_blocks!(mu, a => crate::parallel::product::<T>(par, a, n, f, out, bands))
                    }
                }
            }
            Metric::Free {
                level,
                eta,
                pos,
                radius,
                grad,
                scale,
                wall,
                #[cfg(feature = "periodic")]
                ewald,
                par,
            } => {
                let (f, bands) = tmp.split_at_mut(n);
                spread(bonds, grad, c, scale, f);
                // Nested pairs were refused by the product at these positions.
                #[cfg(feature = "periodic")]
                if let Some(sums) = ewald {
                    if sums
                        .product(eta, pos, radius, f, out, (par, bands))
                        .is_err()
                    {
                        out.fill(T::V3_ZERO);
                    }
                    return;
                }
                let done = match wall {
                    Some(h) if cfg!(feature = "wall") => {
                        wall::free_product(par, level, eta, h, pos, radius, f, out, bands)
                    }
                    _ => crate::parallel::free_product::<T>(
                        par, level, eta, pos, radius, f, out, bands,
                    ),
                };
                if done.is_err() {
                    out.fill(T::V3_ZERO);
                }
            }
            Metric::Drag {
                mu,
                fac,
                sq,
                dt,
                grad,
            } => {
                let m = sq.len();
                let (f, u) = tmp[..2 * m].split_at_mut(m);
                f.fill(T::V3_ZERO);
                spread(bonds, grad, c, T::ONE, &mut f[..n]);
                linalg::sym_matvec::<T>(mu, m, f, u);
                apply_drag(fac, sq, dt, u);
                for (o, &v) in out.iter_mut().zip(u.iter()) {
                    *o = v * dt;
                }
            }
        }
    }
}

/// Tabulates `disp[l * n + q] = (mu_qi - mu_qj) (scale g_l)` from the packed mobility:
/// the values [`Metric::Mobility`] gives (one block difference and one block product per
/// entry, not two products). Blocks stored as `mu_qi` are transposed for
/// [`sym_diff_mul`] (exact: the same bits for symmetric blocks; only a wall's blocks
/// are not symmetric, so without the `wall` feature, or with `sym` (no wall in this
/// step), nothing is transposed and only lower triangles are read). Never
/// inlined: the metric's constructor is inlined at every call site
/// (`mobility_metric`), the table is the same code at each.
#[inline(never)]
pub(crate) fn tabulate<T: Real>(
    mu: Mob<'_, T>,
    bonds: &[Bond<T>],
    grad: &[T::V3],
    scale: T,
    n: usize,
    sym: bool,
    disp: &mut [T::V3],
) {
    // One body per case, so that the block reads branch on nothing at run time.
    match mu {
        Mob::Sym(mu) => table::<T, _, true>(mu, bonds, grad, scale, n, disp),
        Mob::Full(mu) if sym || !cfg!(feature = "wall") => {
            table::<T, _, true>(mu, bonds, grad, scale, n, disp)
        }
        Mob::Full(mu) => table::<T, _, false>(mu, bonds, grad, scale, n, disp),
    }
}

/// [`tabulate`] with the blocks known symmetric (`SYM`) or not.
#[inline(always)]
fn table<T: Real, B: Block<T>, const SYM: bool>(
    mu: &[B],
    bonds: &[Bond<T>],
    grad: &[T::V3],
    scale: T,
    n: usize,
    disp: &mut [T::V3],
) {
    let nb = bonds.len();
    let disp = &mut disp[..n * nb];
    let sym = SYM;
    let tr = |m: T::M3| {
        if cfg!(feature = "wall") && !sym {
            T::transpose(m)
        } else {
            m
        }
    };
    for (l, b) in bonds.iter().enumerate() {
        let g = grad[l] * scale;
        // Bead `q`'s entry of this bond is `disp[l * n + q]` (bond-major).
        let out = &mut disp[l * n..(l + 1) * n];
        if b.one_sphere() {
            for (q, o) in out.iter_mut().enumerate() {
                *o = sym_diff_mul::<T>(sym_block::<T, B>(mu, q, b.i), T::M3_ZERO, g, false);
            }
            continue;
        }
        let (i, j) = (b.i, b.j);
        let (lo, hi) = (i.min(j), i.max(j));
        // The values of `sym_block(q, i) - sym_block(q, j)`, read in three runs of `q` so
        // that no entry decides which triangle holds its blocks: up to `lo` both are in
        // rows `i` and `j` (contiguous); up to `hi` one is in row `hi`, the other in
        // column `lo`; beyond, both in columns `i` and `j` of the rows below.
        let (ri, rj) = (tri(i), tri(j));
        let mut at = 0;
        for (&a, &c) in mu[ri..=ri + lo].iter().zip(&mu[rj..=rj + lo]) {
            out[at] = sym_diff_mul::<T>(a.full(), c.full(), g, sym);
            at += 1;
        }
        let row_hi = &mu[tri(hi)..tri(hi) + hi + 1];
        let mut rq = tri(lo + 1);
        for q in lo + 1..=hi {
            let (on_row, on_col) = (row_hi[q].full(), mu[rq + lo].full());
            let on_col = tr(on_col);
            out[at] = if i == hi {
                sym_diff_mul::<T>(on_row, on_col, g, sym)
            } else {
                sym_diff_mul::<T>(on_col, on_row, g, sym)
            };
            rq += q + 1;
            at += 1;
        }
        for q in hi + 1..n {
            out[at] = sym_diff_mul::<T>(tr(mu[rq + i].full()), tr(mu[rq + j].full()), g, sym);
            rq += q + 1;
            at += 1;
        }
    }
}

/// `f = scale G^T c`: the forces a multiplier vector puts on the beads.
fn spread<T: Real>(bonds: &[Bond<T>], grad: &[T::V3], c: &[T], scale: T, f: &mut [T::V3]) {
    f.fill(T::V3_ZERO);
    for (l, b) in bonds.iter().enumerate() {
        let g = grad[l] * (c[l] * scale);
        f[b.i] += g;
        if !b.one_sphere() {
            f[b.j] -= g;
        }
    }
}

/// [`Metric::Free`]'s `D_l(p)` in a periodic box: `(mu_pi - mu_pj) g` from the Ewald
/// blocks (exactly symmetric, so read in either orientation) with the step's
/// parameters (the product at these positions refused nested spheres).
#[cfg(feature = "periodic")]
fn periodic_at<T: Real>(
    ew: &periodic::Ewald<T>,
    eta: T,
    pos: &[T::V3],
    radius: &[T],
    b: Bond<T>,
    g: T::V3,
    p: usize,
) -> T::V3 {
    let block = |q| periodic::tt_block_at(ew, eta, pos, radius, p, q).unwrap_or(T::M3_ZERO);
    let mu_pj = if b.one_sphere() {
        T::M3_ZERO
    } else {
        block(b.j)
    };
    sym_diff_mul::<T>(block(b.i), mu_pj, g, true)
}
