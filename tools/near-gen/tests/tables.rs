//! The checked-in tables equal a fresh generation, and the kernel's reading of them
//! (singular part plus interpolated remainder, or the far-field series) matches the full
//! 200-term series between the nodes.

use hydrorattle::near::{self, Func};
use hydrorattle_near_gen::recur::Arrays;
use hydrorattle_near_gen::series::{poly, remainder, remainder_coeffs, spec};
use hydrorattle_near_gen::{K_SUM, XI_MAX, emit};

#[test]
fn checked_in_tables_equal_a_fresh_generation() {
    let fresh = emit::source();
    let stored = include_str!("../../../src/near/tables.rs");
    assert!(
        fresh == stored,
        "src/near/tables.rs is stale: run `cargo run --release -p hydrorattle-near-gen`"
    );
}

#[test]
fn kernel_values_match_the_full_series_between_nodes() {
    // Off-node size ratios (half-way in log10) and gaps (half-way in sqrt(xi)), plus the
    // far field on both sides of the switch.
    let lambdas: Vec<f64> = (0..40)
        .map(|i| 10f64.powf(-0.975 + 0.05 * i as f64))
        .collect();
    let mut xis: Vec<f64> = (0..32)
        .map(|j| XI_MAX * ((j as f64 + 0.5) / 32.0).powi(2))
        .collect();
    xis.extend([1e-6, 1e-4, 1.99, 2.01, 3.0, 6.0, 20.0]);
    let mut worst = 0.0f64;
    let mut fam = None;
    let mut arrays = None;
    for f in Func::ALL {
        let family = spec(f).family;
        if fam != Some(family) {
            drop(arrays.take());
            arrays = Some(Arrays::new(family, K_SUM));
            fam = Some(family);
        }
        let c = poly(f, arrays.as_ref().unwrap(), K_SUM);
        let mut worst_f = (0.0f64, 0.0, 0.0);
        for &l in &lambdas {
            let r = remainder_coeffs(f, &c, l);
            for &xi in &xis {
                let exact = near::lubrication::singular_part(f, l, xi) + remainder(&r, xi).0;
                let got = near::value(f, l, 2.0 + xi);
                // Error relative to the function's size, with a floor of 0.1 (where a
                // function crosses zero, or the 12 functions of very unequal spheres are
                // themselves small, the absolute error is what matters).
                let err = (got - exact).abs() / exact.abs().max(0.1);
                if err > worst_f.0 {
                    worst_f = (err, l, xi);
                }
            }
        }
        println!(
            "{f:?}: worst error (relative, floor 0.1) {:.1e} at lambda {:.3}, xi {:.3e}",
            worst_f.0, worst_f.1, worst_f.2
        );
        worst = worst.max(worst_f.0);
    }
    assert!(worst < 1e-4, "{worst}");
}

#[test]
fn the_remainder_series_truncation_stays_within_the_documented_bounds() {
    // The remainder's coefficients fall as k^-3, so its truncation error at K_SUM terms is
    // estimated from the last terms: largest at contact (x = 1).
    let mut fam = None;
    let mut arrays = None;
    for f in Func::ALL {
        let family = spec(f).family;
        if fam != Some(family) {
            drop(arrays.take());
            arrays = Some(Arrays::new(family, K_SUM));
            fam = Some(family);
        }
        let c = poly(f, arrays.as_ref().unwrap(), K_SUM);
        let (mut upto4, mut all) = (0.0f64, 0.0f64);
        for i in 0..41 {
            let l = 10f64.powf(-1.0 + 0.05 * i as f64);
            let r = remainder_coeffs(f, &c, l);
            let tail = remainder(&r, 0.0).1;
            all = all.max(tail);
            if (0.25..=4.0).contains(&l) {
                upto4 = upto4.max(tail);
            }
        }
        println!(
            "{f:?}: truncation at contact <= {upto4:.1e} for 1/4 <= lambda <= 4, {all:.1e} for all"
        );
        assert!(upto4 < 2e-4 && all < 6e-4);
    }
}

#[path = "wall/exact.rs"]
mod wall_exact;
