//! The row-by-row Cholesky factor (`linalg::ordered_*`) that Newton keeps for the
//! active rows of a contact solve: after rows are removed from anywhere and appended at
//! the end, its solve meets the equations of the rows it holds (checked by multiplying
//! back with the matrix), also where a row is dependent on the others.

use hydrorattle::linalg::{
    ordered_append, ordered_build, ordered_null, ordered_remove, ordered_solve,
};

const FLOOR: f64 = 1.4901161193847656e-8;

/// `A = G G^T` for rows `g` (a Gram matrix: positive semi-definite, singular where
/// the rows are dependent).
fn gram(g: &[Vec<f64>]) -> Vec<Vec<f64>> {
    g.iter()
        .map(|a| {
            g.iter()
                .map(|b| a.iter().zip(b).map(|(x, y)| x * y).sum())
                .collect()
        })
        .collect()
}

/// Rows of length `w` from a fixed pattern.
fn rows(count: usize, w: usize) -> Vec<Vec<f64>> {
    (0..count)
        .map(|k| {
            (0..w)
                .map(|c| (((k * 7919 + c * 104_729 + k * c * 31) % 1000) as f64) / 500.0 - 1.0)
                .collect()
        })
        .collect()
}

/// `max |A_S x_S - b_S|` over the rows `order` (relative to the largest `|b|`).
fn residual(a: &[Vec<f64>], order: &[usize], x: &[f64], b: &[f64]) -> f64 {
    let scale = order.iter().fold(0.0f64, |m, &i| m.max(b[i].abs()));
    order
        .iter()
        .map(|&i| (order.iter().map(|&j| a[i][j] * x[j]).sum::<f64>() - b[i]).abs() / scale)
        .fold(0.0, f64::max)
}

/// Solves the rows `order[..m]` of the factor for the right-hand side `A y` (a
/// consistent one), returning the relative residual.
fn check(a: &[Vec<f64>], f: &[f64], n: usize, order: &[usize]) -> f64 {
    let y: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.37).collect();
    let b: Vec<f64> = (0..n)
        .map(|i| order.iter().map(|&j| a[i][j] * y[j]).sum())
        .collect();
    let mut x = b.clone();
    ordered_solve(f, n, order.len(), order, &mut x);
    residual(a, order, &x, &b)
}

#[test]
fn removed_and_appended_rows_solve_their_equations() {
    let n = 40;
    let a = gram(&rows(n, 60));
    let mut order: Vec<usize> = (0..30).collect();
    let mut f = vec![0.0; n * n];
    let d = ordered_build(&mut f, n, 30, FLOOR, |i, j| a[order[i]][order[j]]).unwrap();
    assert_eq!(d, 0);
    assert!(check(&a, &f, n, &order) < 1e-10);
    // Remove from the front, the middle and the end; append rows past them.
    for (remove, append) in [(0, 30), (14, 31), (27, 32), (5, 33), (3, 34)] {
        let p = order.iter().position(|&k| k == remove).unwrap();
        order.remove(p);
        ordered_remove(&mut f, n, order.len() + 1, p, FLOOR, |j| {
            a[order[j]][order[j]]
        });
        assert!(check(&a, &f, n, &order) < 1e-10, "after removing {remove}");
        let m = order.len();
        let dep = ordered_append(&mut f, n, m, FLOOR, a[append][append], |j| {
            a[append][order[j]]
        })
        .unwrap();
        assert!(!dep);
        order.push(append);
        assert!(check(&a, &f, n, &order) < 1e-10, "after appending {append}");
    }
}

#[test]
fn a_dependent_row_turns_independent_when_its_partner_goes() {
    // Row 6 is rows 1 + 2: dependent while both are in the factor, independent once
    // row 2 goes.
    let n = 8;
    let mut g = rows(n, 12);
    g[6] = g[1].iter().zip(&g[2]).map(|(x, y)| x + y).collect();
    let a = gram(&g);
    let mut order: Vec<usize> = (0..7).collect();
    let mut f = vec![0.0; n * n];
    let d = ordered_build(&mut f, n, 7, FLOOR, |i, j| a[order[i]][order[j]]).unwrap();
    assert_eq!(d, 1);
    assert!(check(&a, &f, n, &order) < 1e-10);
    // The self-stress: rows 1 and 2 against row 6, `G^T v = 0`.
    let mut v = vec![9.0; n];
    ordered_null(&f, n, 7, &order, &mut v);
    let net = (0..12)
        .map(|c| v.iter().zip(&g).map(|(x, r)| x * r[c]).sum::<f64>().abs())
        .fold(0.0, f64::max);
    assert!(net < 1e-12, "net force {net}");
    assert_eq!(v[6], 1.0);
    assert!((v[1] + 1.0).abs() < 1e-12 && (v[2] + 1.0).abs() < 1e-12);
    order.remove(2);
    ordered_remove(&mut f, n, 7, 2, FLOOR, |j| a[order[j]][order[j]]);
    assert!(
        (0..6).all(|i| f[i * n + i] > 0.0),
        "row 6 is independent now"
    );
    assert!(check(&a, &f, n, &order) < 1e-10);
    // Appending row 2 again makes the last row (now 2) dependent.
    let dep = ordered_append(&mut f, n, 6, FLOOR, a[2][2], |j| a[2][order[j]]).unwrap();
    assert!(dep);
    order.push(2);
    assert!(check(&a, &f, n, &order) < 1e-10);
}

/// Rows appended one by one after a build of the first of them give the factor a
/// build of all of them gives, bit for bit (each sum from zero in column order, as the
/// factorisation forms it), and its solve the same bits: for every count of rows
/// built first (the appends' sums of 8, 4, 2 and 1 at a time all taken).
#[test]
fn appended_rows_have_the_bits_of_a_build() {
    let n = 23;
    let a = gram(&rows(n, 40));
    let order: Vec<usize> = (0..n).collect();
    let mut whole = vec![0.0; n * n];
    ordered_build(&mut whole, n, n, FLOOR, |i, j| a[i][j]).unwrap();
    let mut x_whole: Vec<f64> = (0..n).map(|i| 1.0 - i as f64 * 0.21).collect();
    let b = x_whole.clone();
    ordered_solve(&whole, n, n, &order, &mut x_whole);
    for first in 0..n {
        let mut f = vec![0.0; n * n];
        ordered_build(&mut f, n, first, FLOOR, |i, j| a[i][j]).unwrap();
        for (m, row) in a.iter().enumerate().skip(first) {
            ordered_append(&mut f, n, m, FLOOR, row[m], |j| row[j]).unwrap();
        }
        for i in 0..n {
            for j in 0..=i {
                assert_eq!(
                    f[i * n + j].to_bits(),
                    whole[i * n + j].to_bits(),
                    "{first} built first: entry ({i}, {j})"
                );
            }
        }
        let mut x = b.clone();
        ordered_solve(&f, n, n, &order, &mut x);
        assert_eq!(x, x_whole, "{first} built first");
    }
}
