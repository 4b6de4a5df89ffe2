//! Caller-owned scratch storage for [`step`](crate::integrate::step): every array a step
//! touches lives here, sized at compile time, so the kernel never allocates.

use crate::constraints::Scratch;
use crate::real::Real;

/// Scratch for up to `N` particles and `B` bonds. Large (`8 N^2` 3x3 blocks); keep one
/// per simulation and reuse it (or place it in a `static`).
#[derive(Clone, Debug)]
pub struct Workspace<T: Real, const N: usize, const B: usize> {
    /// Mobility: `n x n` blocks (`mu_tt`) or `2n x 2n` (grand), row-major, packed.
    pub(crate) mu: [[[T::M3; N]; N]; 4],
    /// Cholesky factor (of the mobility or of the implicit drag operator), or a second
    /// mobility (the overdamped predictor-corrector).
    pub(crate) fac: [[[T::M3; N]; N]; 4],
    /// Dense constraint displacements `D_l(p)`, bond-major.
    pub(crate) disp: [[T::V3; N]; B],
    /// Generalised-vector temporaries (length up to `2n`).
    pub(crate) force: [[T::V3; N]; 2],
    pub(crate) work_a: [[T::V3; N]; 2],
    pub(crate) work_b: [[T::V3; N]; 2],
    pub(crate) work_c: [[T::V3; N]; 2],
    /// Bond vectors at the step's start and at its end.
    pub(crate) grad: [T::V3; B],
    pub(crate) grad_new: [T::V3; B],
    /// Position and velocity multipliers.
    pub(crate) lambda: [T; B],
    pub(crate) kappa: [T; B],
    /// Newton scratch.
    pub(crate) jac: [[T; B]; B],
    pub(crate) rhs: [T; B],
    pub(crate) piv: [usize; B],
    /// `1/m` per particle; `sqrt(m)` then `sqrt(I)` per block row.
    pub(crate) inv_mass: [T; N],
    pub(crate) sqrt_m: [[T; N]; 2],
    /// The candidate state, committed only when the whole step succeeded.
    pub(crate) new_pos: [T::V3; N],
    pub(crate) new_vel: [T::V3; N],
    pub(crate) new_omega: [T::V3; N],
}

impl<T: Real, const N: usize, const B: usize> Default for Workspace<T, N, B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize, const B: usize> Workspace<T, N, B> {
    /// Zeroed scratch (`const`, so it can initialise a `static`).
    pub const fn new() -> Self {
        const { assert!(N > 0, "particle capacity N must be positive") };
        let v = [T::V3_ZERO; N];
        let m = [[T::M3_ZERO; N]; N];
        Self {
            mu: [m; 4],
            fac: [m; 4],
            disp: [v; B],
            force: [v; 2],
            work_a: [v; 2],
            work_b: [v; 2],
            work_c: [v; 2],
            grad: [T::V3_ZERO; B],
            grad_new: [T::V3_ZERO; B],
            lambda: [T::ZERO; B],
            kappa: [T::ZERO; B],
            jac: [[T::ZERO; B]; B],
            rhs: [T::ZERO; B],
            piv: [0; B],
            inv_mass: [T::ZERO; N],
            sqrt_m: [[T::ZERO; N]; 2],
            new_pos: v,
            new_vel: v,
            new_omega: v,
        }
    }

    /// The multipliers of the last position solve (one per bond; force per unit length
    /// along each bond). Meaningful after a successful constrained step; after `Springs`
    /// or a failed step they are stale or partial, and after `Overdamped2` they hold only
    /// the final projection's small correction.
    pub fn multipliers(&self) -> &[T; B] {
        &self.lambda
    }

    /// The translational mobility of the last step's start configuration (`n x n`
    /// blocks, row-major), after a step that assembled it without rotation (with
    /// rotation the storage holds the `2n x 2n` grand mobility). Empty for `n > 2N`.
    pub fn mobility(&self, n: usize) -> &[T::M3] {
        self.mu
            .as_flattened()
            .as_flattened()
            .get(..n * n)
            .unwrap_or(&[])
    }
}

/// The workspace split into named slices sized for one step: `n` particles, `nb`
/// bonds, `m` block rows (`n`, or `2n` when rotation is resolved). Integrators work on
/// these slices only; `N` and `B` stop at [`step`](crate::integrate::step).
pub(crate) struct Views<'a, T: Real> {
    pub mu: &'a mut [T::M3],
    pub fac: &'a mut [T::M3],
    pub disp: &'a mut [T::V3],
    pub force: &'a mut [T::V3],
    pub work_a: &'a mut [T::V3],
    pub work_b: &'a mut [T::V3],
    pub work_c: &'a mut [T::V3],
    pub grad: &'a mut [T::V3],
    pub grad_new: &'a mut [T::V3],
    pub lambda: &'a mut [T],
    pub kappa: &'a mut [T],
    pub inv_mass: &'a mut [T],
    pub sqrt_m: &'a mut [T],
    pub new_pos: &'a mut [T::V3],
    pub new_vel: &'a mut [T::V3],
    pub new_omega: &'a mut [T::V3],
    pub scratch: Scratch<'a, T>,
}

impl<T: Real, const N: usize, const B: usize> Workspace<T, N, B> {
    /// Splits the storage for a step (`n <= N`, `nb <= B`, `m <= 2N` checked by the caller).
    pub(crate) fn views(&mut self, n: usize, nb: usize, m: usize) -> Views<'_, T> {
        Views {
            mu: &mut self.mu.as_flattened_mut().as_flattened_mut()[..m * m],
            fac: &mut self.fac.as_flattened_mut().as_flattened_mut()[..m * m],
            disp: &mut self.disp.as_flattened_mut()[..nb * n],
            force: &mut self.force.as_flattened_mut()[..m],
            work_a: &mut self.work_a.as_flattened_mut()[..m],
            work_b: &mut self.work_b.as_flattened_mut()[..m],
            work_c: &mut self.work_c.as_flattened_mut()[..m],
            grad: &mut self.grad[..nb],
            grad_new: &mut self.grad_new[..nb],
            lambda: &mut self.lambda[..nb],
            kappa: &mut self.kappa[..nb],
            inv_mass: &mut self.inv_mass[..n],
            sqrt_m: &mut self.sqrt_m.as_flattened_mut()[..m],
            new_pos: &mut self.new_pos[..n],
            new_vel: &mut self.new_vel[..n],
            new_omega: &mut self.new_omega[..n],
            scratch: Scratch {
                jac: &mut self.jac.as_flattened_mut()[..nb * nb],
                rhs: &mut self.rhs[..nb],
                piv: &mut self.piv[..nb],
            },
        }
    }
}
