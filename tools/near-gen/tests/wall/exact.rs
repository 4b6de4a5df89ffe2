//! The exact sphere-wall functions for motion parallel to the wall: two independent
//! bispherical solutions agree (reciprocity), the truncation has converged, both ends meet
//! the published limits, and the kernel's reading of the checked-in table matches them.

use hydrorattle::near::wall::wall_scalars;
use hydrorattle_near_gen::emit::{wall_node, wall_source};
use hydrorattle_near_gen::wall::{Motion, force_torque, parallel_exact, terms_for};
use hydrorattle_near_gen::{W_N, W_U_MIN, W_U_STEP};

#[test]
fn checked_in_wall_table_equals_a_fresh_generation() {
    let stored = include_str!("../../../../src/near/wall_table.rs");
    assert!(
        wall_source() == stored,
        "src/near/wall_table.rs is stale: run `cargo run --release -p hydrorattle-near-gen`"
    );
}

/// Gaps from 1e-5 to 50, between and on the nodes.
fn gaps() -> Vec<f64> {
    (0..=4 * (W_N - 1))
        .map(|i| 10f64.powf(W_U_MIN + 0.25 * W_U_STEP * i as f64))
        .collect()
}

#[test]
fn translation_torque_equals_rotation_force_by_reciprocity() {
    // O'Neill's translation and Dean and O'Neill's rotation are separate solutions (own
    // right-hand sides and particular terms); the reciprocal theorem makes the torque of
    // the one equal the force of the other: T/(8 pi eta a^2 U) = (3/4) F/(6 pi eta a^2 W).
    // Both are differences of O(1) sums: about 1e-11 relative near contact, 1e-14
    // absolute far out where the torque is 1e-8.
    let (mut rel, mut abs) = (0.0f64, 0.0f64);
    for d in gaps() {
        let n = terms_for(d);
        let (_, tt) = force_torque(d, Motion::Translation, n);
        let (fr, _) = force_torque(d, Motion::Rotation, n);
        let err = (0.75 * fr - tt).abs();
        abs = abs.max(err);
        if tt > 1e-4 {
            rel = rel.max(err / tt);
        }
    }
    println!("reciprocity: largest difference {abs:.1e}, relative {rel:.1e} where T > 1e-4");
    // Goldman, Cox and Brenner's gaps, h/a = cosh(alpha), for comparison with their table.
    for alpha in [3.0f64, 2.0, 1.5, 1.0, 0.5, 0.3, 0.1] {
        let h = alpha.cosh();
        let [ya, yb, yc] = parallel_exact(h - 1.0);
        println!("h/a {h:.4}: Y^A {ya:.6} Y^B {yb:.4e} Y^C {yc:.6}");
    }
    assert!(abs < 1e-10 && rel < 1e-10, "{abs} {rel}");
}

#[test]
fn truncation_has_converged() {
    // Doubling the coefficients kept changes nothing at the table's precision.
    for d in [1e-5, 1e-3, 0.05, 1.0, 50.0] {
        let n = terms_for(d);
        for m in [Motion::Translation, Motion::Rotation] {
            let (f1, t1) = force_torque(d, m, n);
            let (f2, t2) = force_torque(d, m, 2 * n);
            assert!(
                (f1 - f2).abs() <= 1e-13 * f1 && (t1 - t2).abs() <= 1e-12 * t1,
                "{d} {m:?}"
            );
        }
    }
}

#[test]
fn near_contact_the_exact_values_approach_goldman_cox_and_brenner() {
    // Goldman, Cox and Brenner (1967): Y^A = (8/15) ln(1/d) + 0.9588, Y^B = (1/10) ln(1/d)
    // - 0.1895, Y^C = (2/5) ln(1/d) + 0.3817. The slopes are the lubrication theory's
    // exactly; the constants are their fits to O'Neill's values, to about 1e-2.
    let gcb = |d: f64| {
        let l = (1.0 / d).ln();
        [8.0 / 15.0 * l + 0.9588, 0.1 * l - 0.1895, 0.4 * l + 0.3817]
    };
    let slope = [8.0 / 15.0, 0.1, 0.4];
    let (d1, d2) = (1e-5, 2e-5);
    let (e1, e2) = (parallel_exact(d1), parallel_exact(d2));
    for f in 0..3 {
        let s = (e1[f] - e2[f]) / 2f64.ln();
        println!(
            "function {f}: slope {s:.5} (theory {:.5}), constant {:.4} (GCB {:.4})",
            slope[f],
            e1[f] - slope[f] * (1.0 / d1).ln(),
            gcb(d1)[f] - slope[f] * (1.0 / d1).ln()
        );
        assert!((s - slope[f]).abs() < 1e-3, "{f}: {s}");
    }
    for d in [1e-5, 1e-4, 1e-3, 3e-3] {
        let (e, a) = (parallel_exact(d), gcb(d));
        for f in 0..3 {
            assert!((e[f] - a[f]).abs() < 0.012, "{d} {f}: {} vs {}", e[f], a[f]);
        }
    }
}

/// The method of reflections' mobilities (Faxen's parallel translation, rotation
/// `1 - 5/16 k^3`, coupling `3/32 k^4`, `k = a/h`), inverted.
fn reflections(d: f64) -> [f64; 3] {
    let k = 1.0 / (1.0 + d);
    let mt = 1.0 - 9.0 / 16.0 * k + k.powi(3) / 8.0 - 45.0 / 256.0 * k.powi(4) - k.powi(5) / 16.0;
    let (mr, mc) = (1.0 - 5.0 / 16.0 * k.powi(3), 3.0 / 32.0 * k.powi(4));
    let det = mt * mr - 4.0 / 3.0 * mc * mc;
    [mr / det, mc / det, mt / det]
}

#[test]
fn far_from_the_wall_the_exact_values_approach_the_reflection_series() {
    // The series is exact to the order it keeps: the differences fall as (a/h)^5 or faster.
    for d in [5.0, 10.0, 20.0, 50.0] {
        let k: f64 = 1.0 / (1.0 + d);
        let (e, r) = (parallel_exact(d), reflections(d));
        for f in 0..3 {
            let err = (e[f] - r[f]).abs();
            println!(
                "delta {d}: function {f} exact {:.10} series {:.10}",
                e[f], r[f]
            );
            assert!(err < 0.2 * k.powi(5), "{d} {f}: {err:.1e}");
        }
    }
}

#[test]
fn kernel_values_match_the_exact_solution_at_every_gap() {
    // Between the nodes (cubic interpolation in log10(delta)) and beyond both ends;
    // below the table the error is the O(delta ln delta) remainder left at its first node.
    let mut gs = gaps();
    gs.extend([60.0, 100.0, 300.0]);
    let below = [1e-8, 1e-7, 1e-6, 3e-6, 9.9e-6];
    let mut worst = [[0.0f64; 3]; 2]; // in the table and beyond it, below it
    for &d in gs.iter().chain(&below) {
        let e = parallel_exact(d);
        let w = wall_scalars::<f64>(1.0, 1.0 + d).unwrap();
        let slot = usize::from(d < 1e-5);
        for (f, got) in [w.ya, w.yb, w.yc].into_iter().enumerate() {
            // Relative to Y^A (the coupling's scale in the resistance matrix).
            worst[slot][f] = worst[slot][f].max((got - e[f]).abs() / e[0]);
        }
    }
    println!(
        "kernel against exact, relative to Y^A: {:?} from delta 1e-5 on, {:?} below",
        worst[0], worst[1]
    );
    assert!(worst[0].iter().all(|&x| x < 5e-7), "{worst:?}");
    assert!(worst[1].iter().all(|&x| x < 1e-5), "{worst:?}");
    // At the nodes the kernel returns the table's values.
    for j in [0, 1, W_N / 2, W_N - 2] {
        let d = wall_node(j);
        let e = parallel_exact(d);
        let w = wall_scalars::<f64>(1.0, 1.0 + d).unwrap();
        assert!((w.ya - e[0]).abs() < 1e-12 * e[0], "{j}");
    }
}
