//! Krylov on a contact pile (`docs/CONTACTS.md`, "Krylov on piles"): from the state of
//! the 100-sphere pile of `examples/pile_cost.rs` after 150 Newton steps (landed:
//! contacts and wall links forming and releasing), one step with Krylov gives Newton's
//! positions to the tolerance's order, f32 and f64, and its last constraint solve takes
//! fewer operator products than the band preconditioner in list order did (f64: 400
//! with the band, 314 with the preconditioner on the constraint graph; f32: 257 and
//! 199).

use crate::common::{f64s, norm, pick, sub};
use crate::pile_factor::pile;
use hydrorattle::{
    Contacts, Layout, Method, NoForce, Params, Real, SolverKind, State, Wall, step_slices,
};
use hydrorattle_heap::Buffers;

/// The pile's parameters in `T` with `kind`'s solve.
fn params<T: Real>(kind: SolverKind, n: usize) -> Params<T> {
    let mut p = Params::<T>::new(T::from_f64(0.2));
    p.method = Method::Overdamped;
    p.solver.kind = kind;
    p.solver.tolerance = T::from_f64(pick::<T>(1e-5, 1e-10));
    p.solver.max_iterations = 5000;
    p.wall = Some(Wall::new(T::ZERO));
    p.contacts = Some(Contacts::new(7 * n));
    p
}

/// 150 Newton steps from the drop, then one step from there with Newton and one with
/// Krylov: the largest difference of the positions over the largest radius, and
/// Krylov's operator products.
fn from_the_pile<T: Real>() -> (f64, u32) {
    let (pos0, radius0, density0, bonds0) = pile(15, 3, 100);
    let n = pos0.len();
    let to = |v: &<f64 as Real>::V3| T::v3(T::from_f64(v.x), T::from_f64(v.y), T::from_f64(v.z));
    let mut pos: Vec<T::V3> = pos0.iter().map(to).collect();
    let radius: Vec<T> = radius0.iter().map(|&r| T::from_f64(r)).collect();
    let density: Vec<T> = density0.iter().map(|&d| T::from_f64(d)).collect();
    let bonds: Vec<hydrorattle::Bond<T>> = bonds0
        .iter()
        .map(|b| hydrorattle::Bond {
            i: b.i,
            j: b.j,
            length: T::from_f64(b.length),
        })
        .collect();
    let (newton, krylov) = (
        params::<T>(SolverKind::Newton, n),
        params(SolverKind::Krylov, n),
    );
    let mut buf = Buffers::<T>::new(Layout::for_params(&newton, n, bonds.len()));
    let mut kbuf = Buffers::<T>::new(Layout::for_params(&krylov, n, bonds.len()));
    let (mut vel, mut omega, mut time) = (vec![T::V3_ZERO; n], vec![T::V3_ZERO; n], T::ZERO);
    let mut go = |pos: &mut Vec<T::V3>, time: &mut T, p: &Params<T>, buf: &mut Buffers<T>| {
        let state = State {
            pos,
            vel: &mut vel,
            omega: &mut omega,
            radius: &radius,
            density: &density,
            time,
            noise: None,
        };
        step_slices(state, &bonds, p, &mut buf.workspace(), &mut NoForce).expect("step")
    };
    for _ in 0..150 {
        go(&mut pos, &mut time, &newton, &mut buf);
    }
    let (mut a, mut b) = (pos.clone(), pos);
    let (mut ta, mut tb) = (time, time);
    go(&mut a, &mut ta, &newton, &mut buf);
    let report = go(&mut b, &mut tb, &krylov, &mut kbuf);
    let d = (0..n)
        .map(|i| norm(sub(f64s::<T>(a[i]), f64s::<T>(b[i]))))
        .fold(0.0, f64::max);
    (d / 1.5, report.iterations)
}

fn agrees_in_few_products<T: Real>() {
    let (d, products) = from_the_pile::<T>();
    eprintln!("Krylov against Newton: {d:.2e}, {products} products");
    // Both solves stop at the tolerance (relative lengths): positions agree to its
    // order times the pile's conditioning (f64: 8.5e-8 of a radius, 8.1e-9 with the
    // band; f32: 1.3e-5, 3.5e-5).
    let tol = pick::<T>(1e-3, 1e-6);
    assert!(d <= tol, "Krylov and Newton differ by {d:e} of a radius");
    // The band in list order took 400 products here (f32: 257), the graph's IC(0)
    // 314 (199).
    let most = pick::<T>(230.0, 360.0);
    assert!(f64::from(products) <= most, "{products} products");
}

#[test]
fn krylov_on_a_pile_agrees_in_few_products_f64() {
    agrees_in_few_products::<f64>();
}

#[test]
fn krylov_on_a_pile_agrees_in_few_products_f32() {
    agrees_in_few_products::<f32>();
}
