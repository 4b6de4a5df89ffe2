//! The chart of a collected sweep: an observable against a parameter, one series per
//! setting of the other parameters that vary, each point the mean over its replicas
//! with the standard error of the mean as an error bar.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

use crate::render::{LineChart, Series, line_chart_with_errors};

/// A series of the chart: its name (the other parameters' values) and, per value of
/// the parameter, the mean of the column and the standard error of the mean.
type Means = (String, Vec<(f64, f64, f64)>);

/// Column `yi` against column `xi` of the done rows: one series per setting of the other
/// parameters that vary (columns 2 to `params_end`, replicas and their seeds left out),
/// each point the mean over the rows with that `x` (replicas) with its standard error
/// (sample standard deviation over the square root of the count; 0 for one row).
fn replica_means(
    header: &[String],
    table: &[Vec<String>],
    (xi, yi): (usize, usize),
    params_end: usize,
) -> Vec<Means> {
    let varies = |c: usize| table.iter().any(|r| r[c] != table[0][c]);
    let others: Vec<usize> = (2..params_end)
        .filter(|&c| c != xi && header[c] != "replica" && header[c] != "brownian.seed")
        .filter(|&c| varies(c))
        .collect();
    let mut groups: Vec<(String, BTreeMap<String, Vec<f64>>)> = Vec::new();
    for row in table.iter().filter(|r| r[params_end] == "done") {
        let (Ok(_), Ok(v)) = (row[xi].parse::<f64>(), row[yi].parse::<f64>()) else {
            continue;
        };
        let name: Vec<String> = others
            .iter()
            .map(|&c| format!("{}={}", header[c], row[c]))
            .collect();
        let name = name.join(" ");
        let k = match groups.iter().position(|g| g.0 == name) {
            Some(k) => k,
            None => {
                groups.push((name, BTreeMap::new()));
                groups.len() - 1
            }
        };
        groups[k].1.entry(row[xi].clone()).or_default().push(v);
    }
    groups
        .into_iter()
        .map(|(name, by_x)| {
            let mut pts: Vec<(f64, f64, f64)> = by_x
                .iter()
                .map(|(xv, vals)| {
                    let n = vals.len() as f64;
                    let mean = vals.iter().sum::<f64>() / n;
                    let sem = if vals.len() > 1 {
                        let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
                        (var / n).sqrt()
                    } else {
                        0.0
                    };
                    (xv.parse().unwrap_or(f64::NAN), mean, sem)
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            (name, pts)
        })
        .collect()
}

/// Draws column `y` against parameter `x` ([`replica_means`]) into `DIR/Y_vs_X.png`.
pub(super) fn draw(
    dir: &Path,
    header: &[String],
    table: &[Vec<String>],
    x: &str,
    y: &str,
    replicas: bool,
) -> Result<PathBuf> {
    let col = |name: &str| header.iter().position(|h| h == name);
    let params_end = col("status").unwrap_or(2);
    let xi = col(x).filter(|&c| (2..params_end).contains(&c));
    let Some(xi) = xi else {
        let params = header[2..params_end].join(", ");
        bail!("--x {x:?} is not a parameter of this sweep ({params})");
    };
    let Some(yi) = col(y) else {
        bail!(
            "--y {y:?} is not a column of collected.csv ({})",
            header.join(", ")
        );
    };
    let means = replica_means(header, table, (xi, yi), params_end);
    if means.is_empty() {
        bail!("no finished point has numbers in {x:?} and {y:?}");
    }
    let series = means
        .iter()
        .map(|(name, pts)| Series {
            name: name.clone(),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
        })
        .collect();
    let errors: Vec<Vec<f64>> = means
        .iter()
        .map(|m| m.1.iter().map(|p| p.2).collect())
        .collect();
    let chart = LineChart {
        title: if replicas {
            format!("{y} against {x} (mean over replicas, bars: standard error)")
        } else {
            format!("{y} against {x}")
        },
        x_label: x.to_string(),
        y_label: y.to_string(),
        series,
        ..LineChart::default()
    };
    let safe = |s: &str| s.replace(|c: char| !c.is_ascii_alphanumeric() && c != '_', "_");
    let path = dir.join(format!("{}_vs_{}.png", safe(y), safe(x)));
    line_chart_with_errors(&path, &chart, &errors, (900, 600))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replica_means_are_means_with_standard_errors() {
        let header: Vec<String> = [
            "id",
            "index",
            "T",
            "dt",
            "brownian.seed",
            "replica",
            "status",
            "y",
        ]
        .map(String::from)
        .to_vec();
        let row = |t: &str, dt: &str, seed: &str, y: &str| -> Vec<String> {
            ["x", "0", t, dt, seed, "0", "done", y]
                .map(String::from)
                .to_vec()
        };
        let table = vec![
            row("1", "0.1", "1", "1"),
            row("1", "0.1", "2", "2"),
            row("1", "0.1", "3", "6"),
            row("2", "0.1", "1", "4"),
            row("1", "0.2", "1", "5"),
        ];
        let m = replica_means(&header, &table, (2, 7), 6);
        // dt varies: two series; T = 1 at dt = 0.1 has three replicas 1, 2, 6:
        // mean 3, sample variance (4 + 1 + 9) / 2 = 7, standard error sqrt(7 / 3).
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].0, "dt=0.1");
        assert_eq!(m[0].1[0], (1.0, 3.0, (7.0f64 / 3.0).sqrt()));
        assert_eq!(m[0].1[1], (2.0, 4.0, 0.0));
        assert_eq!(m[1], ("dt=0.2".to_string(), vec![(1.0, 5.0, 0.0)]));
    }
}
