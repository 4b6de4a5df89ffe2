//! Constraint solves: the SHAKE sweep, a Newton solve on the whole Jacobian, and the
//! RATTLE velocity sweep — all on one generic problem.
//!
//! A unit multiplier on bond `l` moves bead `p` by `D_l(p)` ([`Metric`]). The position
//! problem finds `lambda` with `|x_i - x_j|^2 = d^2` for `x = x* + sum_l lambda_l D_l`
//! (paper eq. 3); the velocity problem finds `kappa` with `b_k . (v_i - v_j) = 0` for
//! `v = v* + sum_l kappa_l D_l` (paper eq. 4), `b_k` the bond vectors at the new positions.

use crate::bonds::Bond;
use crate::error::{Stage, StepError};
use crate::linalg;
use crate::real::Real;

/// Which algorithm solves for the multipliers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolverKind {
    /// Cyclic sweeps, one constraint at a time in bond order (the paper's SHAKE/RATTLE).
    Sweep,
    /// Newton iterations on the dense `bonds x bonds` Jacobian (LU, reused while it
    /// keeps converging fast), the default.
    #[default]
    Newton,
}

/// Tolerance and iteration cap for a constraint solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solver<T> {
    /// Algorithm.
    pub kind: SolverKind,
    /// Largest accepted relative bond-length error `| |r_ij| - d | / d` (positions), or
    /// relative length change per step `dt |b.(v_i - v_j)| / d^2` (velocities).
    pub tolerance: T,
    /// Iteration cap (sweeps or Newton steps); reaching it is an error.
    pub max_iterations: u32,
}

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
    /// Precomputed dense displacements `disp[l * n + p]` (the hydrodynamic metric
    /// `dt mu G^T` moves every bead).
    Dense {
        /// Displacements, bond-major.
        disp: &'a [T::V3],
        /// Beads.
        n: usize,
    },
}

impl<T: Real> Metric<'_, T> {
    /// Displacement of bead `p` per unit multiplier on bond `l`.
    #[inline]
    fn at(&self, bonds: &[Bond<T>], l: usize, p: usize) -> T::V3 {
        match *self {
            Metric::Mass {
                inv_mass,
                grad,
                scale,
            } => {
                let b = bonds[l];
                if p == b.i {
                    grad[l] * (scale * inv_mass[p])
                } else if p == b.j {
                    grad[l] * (-scale * inv_mass[p])
                } else {
                    T::V3_ZERO
                }
            }
            Metric::Dense { disp, n } => disp[l * n + p],
        }
    }

    /// `x += c D_l`.
    fn apply(&self, bonds: &[Bond<T>], l: usize, c: T, x: &mut [T::V3]) {
        match *self {
            Metric::Mass { .. } => {
                let b = bonds[l];
                x[b.i] += self.at(bonds, l, b.i) * c;
                x[b.j] += self.at(bonds, l, b.j) * c;
            }
            Metric::Dense { disp, n } => {
                for (xp, &d) in x.iter_mut().zip(&disp[l * n..l * n + n]) {
                    *xp += d * c;
                }
            }
        }
    }

    /// Change of bond `k`'s vector per unit multiplier on bond `l`.
    #[inline]
    fn relative(&self, bonds: &[Bond<T>], k: usize, l: usize) -> T::V3 {
        let b = bonds[k];
        self.at(bonds, l, b.i) - self.at(bonds, l, b.j)
    }
}

/// Which condition to enforce.
#[derive(Clone, Copy, Debug)]
pub enum Problem<'a, T: Real> {
    /// `|x_i - x_j|^2 - d^2 = 0` (SHAKE).
    Positions,
    /// `b_k . (x_i - x_j) = 0` with `b_k` the new bond vectors (RATTLE); `dt` scales the
    /// residual to a relative length change per step.
    Velocities {
        /// Bond vectors at the new positions.
        bond: &'a [T::V3],
        /// Time step.
        dt: T,
    },
}

impl<T: Real> Problem<'_, T> {
    /// Residual of bond `k`, its derivative direction (w.r.t. `x_i - x_j`), and the
    /// normalised magnitude compared with the tolerance.
    #[inline]
    fn eval(&self, b: &Bond<T>, k: usize, x: &[T::V3]) -> (T, T::V3, T) {
        let rel = x[b.i] - x[b.j];
        let d2 = b.length * b.length;
        match *self {
            Problem::Positions => {
                let s = T::norm2(rel) - d2;
                (s, rel * T::TWO, s.abs() / (T::TWO * d2))
            }
            Problem::Velocities { bond, dt } => {
                let c = T::dot(bond[k], rel);
                (c, bond[k], (c * dt).abs() / d2)
            }
        }
    }

    fn stage(&self) -> Stage {
        match self {
            Problem::Positions => Stage::Positions,
            Problem::Velocities { .. } => Stage::Velocities,
        }
    }

    fn no_convergence(&self, iterations: u32, residual: T) -> StepError {
        StepError::NoConvergence {
            stage: self.stage(),
            iterations,
            residual: residual.to_f64(),
        }
    }
}

/// Outcome of a converged solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats<T> {
    /// Sweeps or Newton steps taken.
    pub iterations: u32,
    /// Largest normalised residual left.
    pub residual: T,
}

/// Scratch for the Newton solve: `jac` holds `bonds^2` entries, `rhs` and `piv` `bonds`.
pub struct Scratch<'a, T> {
    /// Jacobian (row-major).
    pub jac: &'a mut [T],
    /// Right-hand side / update.
    pub rhs: &'a mut [T],
    /// LU pivots.
    pub piv: &'a mut [usize],
}

/// Largest normalised residual over all bonds.
fn worst<T: Real>(problem: &Problem<'_, T>, bonds: &[Bond<T>], x: &[T::V3]) -> T {
    let mut w = T::ZERO;
    for (k, b) in bonds.iter().enumerate() {
        w = w.max_sticky(problem.eval(b, k, x).2);
    }
    w
}

/// Solves for the multipliers, accumulating them into `mult` and moving `x`.
pub fn solve<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    match solver.kind {
        SolverKind::Sweep => sweep(problem, metric, bonds, solver, x, mult),
        SolverKind::Newton => newton(problem, metric, bonds, solver, x, mult, scratch),
    }
}

/// The SHAKE (positions) / RATTLE (velocities) sweep: one constraint at a time, each
/// update the exact linearisation of that constraint alone (paper eqs. 3 and 4).
pub fn sweep<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
) -> Result<SolveStats<T>, StepError> {
    for it in 0..=solver.max_iterations {
        let mut residual = T::ZERO;
        let mut moved = false;
        for (k, b) in bonds.iter().enumerate() {
            let (value, dir, r) = problem.eval(b, k, x);
            residual = residual.max_sticky(r);
            if r <= solver.tolerance || it == solver.max_iterations {
                continue;
            }
            let w = metric.relative(bonds, k, k);
            let den = T::dot(dir, w);
            // A vanishing denominator means the bond turned ~90 degrees in one step.
            let floor = T::from_f64(1e-12) * T::norm(dir) * T::norm(w);
            if !(den.abs() > floor) {
                return Err(StepError::Degenerate { bond: k });
            }
            let delta = -value / den;
            mult[k] += delta;
            metric.apply(bonds, k, delta, x);
            moved = true;
        }
        if !residual.is_finite() {
            return Err(problem.no_convergence(it, residual));
        }
        if !moved && residual <= solver.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual,
            });
        }
        if it == solver.max_iterations {
            return Err(problem.no_convergence(it, residual));
        }
    }
    // The loop returns on its last pass; this is the empty-range case (cap 0 handled above).
    Ok(SolveStats::default())
}

/// Newton iterations on the dense Jacobian `J_kl = dir_k . (D_l(i_k) - D_l(j_k))`,
/// solved by LU. The factorisation is reused while the residual falls at least
/// tenfold per iteration (a chord / quasi-Newton step: the Jacobian barely changes
/// within one time step) and refreshed otherwise. Velocities are linear: one step.
pub fn newton<T: Real>(
    problem: Problem<'_, T>,
    metric: &Metric<'_, T>,
    bonds: &[Bond<T>],
    solver: &Solver<T>,
    x: &mut [T::V3],
    mult: &mut [T],
    scratch: &mut Scratch<'_, T>,
) -> Result<SolveStats<T>, StepError> {
    let nb = bonds.len();
    let (jac, rhs, piv) = (
        &mut scratch.jac[..nb * nb],
        &mut scratch.rhs[..nb],
        &mut scratch.piv[..nb],
    );
    let mut previous: Option<T> = None;
    for it in 0..=solver.max_iterations {
        let residual = worst(&problem, bonds, x);
        if !residual.is_finite() {
            return Err(problem.no_convergence(it, residual));
        }
        if residual <= solver.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual,
            });
        }
        if it == solver.max_iterations {
            return Err(problem.no_convergence(it, residual));
        }
        let refresh = match previous {
            None => true,
            Some(p) => !(residual <= p * T::from_f64(0.1)),
        };
        previous = Some(residual);
        for (k, b) in bonds.iter().enumerate() {
            let (value, dir, _) = problem.eval(b, k, x);
            rhs[k] = -value;
            if refresh {
                for l in 0..nb {
                    jac[k * nb + l] = T::dot(dir, metric.relative(bonds, k, l));
                }
            }
        }
        if refresh {
            linalg::lu(jac, nb, piv).map_err(|error| StepError::Linalg {
                stage: problem.stage(),
                error,
            })?;
        }
        linalg::lu_solve(jac, nb, piv, rhs);
        for l in 0..nb {
            mult[l] += rhs[l];
            metric.apply(bonds, l, rhs[l], x);
        }
    }
    // The loop returns on its last pass (it == max_iterations).
    Err(StepError::NoConvergence {
        stage: problem.stage(),
        iterations: solver.max_iterations,
        residual: f64::NAN,
    })
}
