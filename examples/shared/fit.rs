//! The examples' cost-model fits (shared by `#[path]`).

/// Non-negative least squares on relative residuals, by dropping the most negative
/// coefficient and refitting: `x` rows of terms (a 1 column for a constant), `t` times.
pub fn fit(x: &[Vec<f64>], t: &[f64]) -> Vec<f64> {
    let k = x[0].len();
    let mut on = vec![true; k];
    loop {
        let cols: Vec<usize> = (0..k).filter(|&c| on[c]).collect();
        let m = cols.len();
        let mut a = vec![vec![0.0; m + 1]; m];
        for (row, &ti) in x.iter().zip(t) {
            let w: Vec<f64> = cols.iter().map(|&c| row[c] / ti).collect();
            for i in 0..m {
                for j in 0..m {
                    a[i][j] += w[i] * w[j];
                }
                a[i][m] += w[i];
            }
        }
        // Gauss-Jordan with partial pivoting.
        for i in 0..m {
            let p = (i..m)
                .max_by(|&r, &s| a[r][i].abs().total_cmp(&a[s][i].abs()))
                .unwrap();
            a.swap(i, p);
            let pivot = a[i].clone();
            for (r, row) in a.iter_mut().enumerate() {
                if r != i {
                    let f = row[i] / pivot[i];
                    for (x, p) in row.iter_mut().zip(&pivot).skip(i) {
                        *x -= f * p;
                    }
                }
            }
        }
        let mut out = vec![0.0; k];
        for (i, &c) in cols.iter().enumerate() {
            out[c] = a[i][m] / a[i][i];
        }
        match (0..k)
            .filter(|&c| on[c])
            .min_by(|&a, &b| out[a].total_cmp(&out[b]))
        {
            Some(c) if out[c] < 0.0 => on[c] = false,
            _ => return out,
        }
    }
}

/// The fit's worst relative misfit (a factor, 1 for a perfect fit): a check of the
/// model's form.
pub fn misfit(x: &[Vec<f64>], t: &[f64], c: &[f64]) -> f64 {
    x.iter()
        .zip(t)
        .map(|(r, &ti)| {
            (r.iter().zip(c).map(|(a, b)| a * b).sum::<f64>() / ti)
                .ln()
                .abs()
        })
        .fold(0.0, f64::max)
        .exp()
}
