//! What the free-space cost tests share: the shapes the cost examples measure, the
//! recorded cells of `bench/results/free_cost.csv`, and the check that the model's pick
//! costs, as measured, at most 1.2 times the fastest path that ran.

use std::collections::HashMap;

use super::free_cost::FreeChoice;

/// The shapes the free-space examples measure, by the name their rows carry: the clouds
/// at three volume fractions (`Some(phi)`), and the helical chain (`None`).
pub(super) const SHAPES: [(&str, Option<f64>); 4] = [
    ("cloud 0.01", Some(0.01)),
    ("cloud 0.1", Some(0.1)),
    ("cloud 0.3", Some(0.3)),
    ("chain", None),
];

/// The rows of the table `table` in `bench/results/free_cost.csv`, as fields.
fn rows(table: &str) -> impl Iterator<Item = Vec<String>> {
    let csv = include_str!("../../../bench/results/free_cost.csv");
    csv.lines()
        .skip(1)
        .map(crate::output::csv_fields)
        .filter(move |row| row[5] == table)
}

/// The recorded cells of `table`: `(case, quantity) -> value`, later rows over earlier.
pub(super) fn cells(table: &str) -> HashMap<(String, String), String> {
    rows(table)
        .map(|row| ((row[6].clone(), row[7].clone()), row[8].clone()))
        .collect()
}

/// The recorded numbers of `table`: `(case, quantity) -> value`, later numbers over
/// earlier; cells that are not numbers (a refusal) are skipped.
pub(super) fn numbers(table: &str) -> HashMap<(String, String), f64> {
    rows(table)
        .filter_map(|row| Some(((row[6].clone(), row[7].clone()), row[8].parse().ok()?)))
        .collect()
}

/// The model's picks checked against the measured paths, and the ones that were wrong.
#[derive(Default)]
pub(super) struct Picks {
    checked: usize,
    wrong: Vec<String>,
}

impl Picks {
    /// Checks that `pick`, the model's choice for `case`, costs as measured at most 1.2
    /// times the fastest of `measured` (the paths that ran, with their times); a pick
    /// that was not measured is wrong.
    pub(super) fn check(&mut self, case: &str, pick: FreeChoice, measured: &[(FreeChoice, f64)]) {
        let best = measured.iter().map(|m| m.1).fold(f64::INFINITY, f64::min);
        let got = measured.iter().find(|m| m.0 == pick).map(|m| m.1);
        self.checked += 1;
        if got.is_none_or(|g| g > 1.2 * best) {
            self.wrong.push(format!(
                "{case}: picks {pick:?} ({got:?} s measured), best {best:.3e} of {measured:?}"
            ));
        }
    }

    /// Asserts that at least `least` cases were checked and none was wrong.
    pub(super) fn assert_all(self, least: usize) {
        let Self { checked, wrong } = self;
        assert!(checked >= least, "{checked} cases");
        assert!(
            wrong.is_empty(),
            "{} of {checked}:\n{}",
            wrong.len(),
            wrong.join("\n")
        );
    }
}
