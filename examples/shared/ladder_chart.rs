//! `near_ladder chart`: the speed-accuracy chart from the latest records of
//! `bench/results/near_ladder.csv` (the last row of each measurement, case and
//! quantity): x the cost of a step, y each check's relative error against its exact
//! value; one panel for the Figure 1 (c) chain (stepped as every rung can: `Overdamped`,
//! Krylov, no contacts), one for 1,000 spheres in a box. A rung the kernel refuses, or
//! one not measured, is named under its panel.

use std::collections::HashMap;

use super::svg::{Panel, Point, chart};
use super::{ACCURACY, CHAIN_KRYLOV, EXACT, RUNGS, box_table};

/// Errors shown below this are drawn at it (a log axis has no zero).
const FLOOR: f64 = 1e-6;

/// The fields of one CSV line (double quotes around fields with commas).
fn fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur)),
            c => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// The chart's SVG from the records' text.
pub fn draw(records: &str) -> String {
    let mut latest: HashMap<(String, String, String), String> = HashMap::new();
    for line in records.lines().skip(1) {
        let f = fields(line);
        if let [.., m, case, q, v] = &f[..] {
            latest.insert((m.clone(), case.clone(), q.clone()), v.clone());
        }
    }
    let get = |m: &str, case: &str, q: &str| latest.get(&(m.into(), case.into(), q.into()));
    let panel = |title: &str, table: &str| {
        let (mut points, mut notes) = (Vec::new(), Vec::new());
        for (k, (name, _, _)) in RUNGS.iter().enumerate() {
            let cost = get(table, name, "s a step");
            let Some(x) = cost.and_then(|c| c.parse::<f64>().ok()) else {
                let why = cost.map_or("not measured", |c| c.as_str());
                notes.push(format!("{name}: {why}"));
                continue;
            };
            for (quantity, label, _) in EXACT {
                let e = get(ACCURACY, name, &format!("{quantity}, relative error"));
                match e.and_then(|e| e.parse::<f64>().ok()) {
                    Some(e) => points.push(Point {
                        x,
                        y: e.abs().max(FLOOR),
                        series: k,
                        label: match e.abs() < 1e-3 {
                            true => format!("{label} {e:+.0e}"),
                            false => format!("{label} {:+.1}%", 100.0 * e),
                        },
                    }),
                    None => notes.push(format!("{name}, {label}: refused")),
                }
            }
        }
        Panel {
            title: title.into(),
            x_label: "seconds a step (one core)".into(),
            y_label: format!("relative error (drawn at {FLOOR:.0e} if below)"),
            points,
            notes,
        }
    };
    let names: Vec<&str> = RUNGS.iter().map(|r| r.0).collect();
    chart(
        "Model ladder: cost of a step against error from exact two-sphere and wall values",
        &names,
        &[
            panel(
                "Figure 1 (c) chain, 25 spheres (Overdamped, Krylov)",
                CHAIN_KRYLOV,
            ),
            panel("1,000 spheres in a periodic box", &box_table(1000)),
        ],
    )
}
