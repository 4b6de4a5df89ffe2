//! The midpoint reads the mobility it assembled at `x~`, whatever storage holds it:
//! a thermal kick by Lanczos (a 12-bead zigzag chain, free space) with the midpoint's
//! mobility in the workspace's six-scalar blocks ([`Views::mu2`]) against the same
//! kick with it in nine-scalar blocks, and both against the midpoint's drift computed
//! here from a mobility assembled at `x~` into nine-scalar blocks of the test's own.
//! Every slot of the workspace is NaN before the kick, so a read of a slot the kick
//! did not write (the start's mobility, the factor's storage) shows.

use super::*;
use crate::constraints::Metric;
use crate::linalg::{sym_matvec, tri};
use crate::mobility::assemble_tt;
use crate::parallel::Serial;
use crate::params::NoiseSqrt;
use crate::workspace::{Layout, Workspace};

const N: usize = 12;
const B: usize = N - 1;
const BLOCKS: usize = tri(N);

/// A zigzag chain of unit spheres, bonds 2.4 long (`x` apart 2.2, `y` 0 or 0.96).
fn chain<T: Real>() -> ([T::V3; N], [Bond<T>; B]) {
    let pos = core::array::from_fn(|i| {
        let y = if i % 2 == 1 { 0.96 } else { 0.0 };
        T::v3_from([2.2 * i as f64, y, 0.1 * i as f64])
    });
    let bonds = core::array::from_fn(|k| Bond {
        i: k,
        j: k + 1,
        length: T::norm2(pos[k + 1] - pos[k]).sqrt(),
    });
    (pos, bonds)
}

fn params<T: Real>() -> (Params<T>, Brownian<T>) {
    let mut p = Params::new(T::from_f64(0.01));
    p.gravity = T::V3_ZERO;
    p.noise_sqrt = NoiseSqrt::Lanczos;
    p.lanczos.max_iterations = 16;
    let b = Brownian {
        temperature: T::ONE,
        drift: Drift::Midpoint,
    };
    p.brownian = Some(b);
    (p, b)
}

/// Storage of one kick, every slot NaN.
struct Store<T: Real> {
    blocks: [T::M3; BLOCKS],
    vectors: [T::V3; 1024],
    scalars: [T; 2048],
    indices: [usize; 64],
}

impl<T: Real> Store<T> {
    fn new() -> Self {
        let nan = T::from_f64(f64::NAN);
        let v = T::v3(nan, nan, nan);
        Self {
            blocks: [T::m3_cols(v, v, v); BLOCKS],
            vectors: [v; 1024],
            scalars: [nan; 2048],
            indices: [0; 64],
        }
    }
}

/// The outcome of a kick: `dx`, the midpoint `x~`, the scaled `L^-T xi`, the Lanczos
/// and the projection's iterations.
type Kicked<T> = (
    [<T as Real>::V3; N],
    [<T as Real>::V3; N],
    [<T as Real>::V3; N],
    u32,
    u32,
);

/// A kick with the midpoint's mobility in the workspace's symmetric blocks (`nine`:
/// `None`) or in `nine`.
fn kicked<T: Real>(nine: Option<&mut [T::M3]>) -> Result<Kicked<T>, StepError> {
    let (p, b) = params::<T>();
    let (pos, bonds) = chain::<T>();
    let layout = Layout::for_params(&p, N, B);
    let mut st = Store::<T>::new();
    assert!(layout.blocks == 0 && layout.vectors <= 1024 && layout.scalars <= 2048);
    assert!(layout.indices <= 64);
    let mut ws = Workspace::new(
        &mut st.blocks[..0],
        &mut st.vectors[..layout.vectors],
        &mut st.scalars[..layout.scalars],
        &mut st.indices[..layout.indices],
    );
    let v = ws.views(&p, N, B)?;
    let Views {
        mut mu,
        mu2,
        fac,
        work_b: dx,
        new_vel: xi,
        new_omega: mid,
        grad_new,
        disp,
        kappa,
        mut scratch,
        bands,
        basis,
        krylov_t,
        ..
    } = v;
    assert!(
        matches!(&mu2, MobMut::Sym(a) if a.len() == BLOCKS),
        "{mu2:?}"
    );
    assert!(fac.is_empty());
    let radius = [T::ONE; N];
    let zero = [T::V3_ZERO; N];
    let s = Start {
        pos: &pos,
        vel: &zero,
        omega: &zero,
        radius: &radius,
        density: &radius,
        ewald: None,
    };
    with_blocks!(mut mu.reborrow(), a => assemble_tt(p.hydro, p.viscosity, &pos, &radius, a))?;
    let held = Held {
        bonds: &bonds,
        grad_mid: grad_new,
        disp,
        kappa,
        scratch: &mut scratch,
    };
    let krylov = Krylov {
        basis,
        work: krylov_t,
        par: &Serial,
        bands,
        copied: false,
        at_mid: match nine {
            Some(a) => MobMut::Full(a),
            None => mu2,
        },
        near: (&mut [], &mut [], &core::cell::Cell::new(0)),
    };
    let mut noise = Noise::new(5);
    let mu = mu.into_ref();
    let held = Some(held);
    let (lanczos, projected) = kick(&p, b, &s, mu, fac, xi, mid, dx, &mut noise, held, krylov)?;
    let copy = |x: &[T::V3]| core::array::from_fn(|i| x[i]);
    Ok((copy(dx), copy(mid), copy(xi), lanczos, projected))
}

fn bits<T: Real>(x: &[T::V3]) -> [[u64; 3]; N] {
    core::array::from_fn(|i| T::xyz(x[i]).map(|c| c.to_f64().to_bits()))
}

fn midpoint_reads_its_own_mobility<T: Real>() -> Result<(), StepError> {
    let nan = T::from_f64(f64::NAN);
    let v = T::v3(nan, nan, nan);
    let mut nine = [T::m3_cols(v, v, v); BLOCKS];
    let (dx, mid, xi, lanczos, projected) = kicked::<T>(None)?;
    let (dx9, mid9, xi9, lanczos9, projected9) = kicked::<T>(Some(&mut nine))?;
    assert!(lanczos > 1 && projected > 0, "{lanczos} {projected}");
    assert_eq!((lanczos, projected), (lanczos9, projected9));
    assert_eq!(bits::<T>(&mid), bits::<T>(&mid9));
    assert_eq!(bits::<T>(&xi), bits::<T>(&xi9));
    assert_eq!(
        bits::<T>(&dx),
        bits::<T>(&dx9),
        "six against nine scalars a block"
    );
    // The drift from the test's own nine-scalar mobility at `x~`: `mu(x~) xi`, then
    // projected onto the bonds at `x~` with the midpoint's solver.
    let (p, _) = params::<T>();
    let (_, bonds) = chain::<T>();
    let radius = [T::ONE; N];
    let mut reference = [T::M3_ZERO; BLOCKS];
    assemble_tt(p.hydro, p.viscosity, &mid, &radius, &mut reference)?;
    let mut want = [T::V3_ZERO; N];
    sym_matvec::<T>(&reference, N, &xi, &mut want);
    let layout = Layout::for_params(&p, N, B);
    let mut st = Store::<T>::new();
    let mut ws = Workspace::new(
        &mut st.blocks[..0],
        &mut st.vectors[..layout.vectors],
        &mut st.scalars[..layout.scalars],
        &mut st.indices[..layout.indices],
    );
    let Views {
        grad_new: grad,
        disp,
        kappa,
        mut scratch,
        ..
    } = ws.views(&p, N, B)?;
    bond_vectors(&bonds, &mid, None, grad);
    kappa.fill(T::ZERO);
    let mu = Mob::Full(&reference);
    let metric: Metric<'_, T> = mobility_metric(
        &p,
        None,
        &bonds,
        &mid,
        &radius,
        mu,
        grad,
        T::ONE,
        disp,
        (&Serial, &[]),
    );
    let solver = midpoint_solver(&p, true, &bonds, grad, &want);
    let problem = Problem::Velocities {
        bond: grad,
        dt: T::ONE,
    };
    let stats = constraints::solve(
        problem,
        &metric,
        &bonds,
        &solver,
        &mut want,
        kappa,
        &mut scratch,
    )?;
    assert_eq!(stats.iterations, projected);
    assert_eq!(bits::<T>(&dx), bits::<T>(&want), "the drift from mu(x~)");
    Ok(())
}

#[test]
fn midpoint_reads_its_own_mobility_f64() -> Result<(), StepError> {
    midpoint_reads_its_own_mobility::<f64>()
}

#[test]
fn midpoint_reads_its_own_mobility_f32() -> Result<(), StepError> {
    midpoint_reads_its_own_mobility::<f32>()
}
