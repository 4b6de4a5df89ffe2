//! How robust each claim is: its verdict in every variant of the sensitivity study
//! (`claims_variants.csv`) and, per claim, in how many variants it holds
//! (`claims_sensitivity.csv`).

use std::path::Path;

use anyhow::Result;

use super::{CaseRun, SPECS, Verdict, claims};
use hydrorattle_host::output::{AtomicFile, CsvWriter};

/// Writes `claims_variants.csv` and `claims_sensitivity.csv` under `out` from the runs of
/// every variant (`variants[v]` names variant `v` as parameter and value, `runs[v]`
/// holds its cases), and returns the second as a printable table.
pub fn claim_tables(
    out: &Path,
    variants: &[(String, String)],
    runs: &[Vec<CaseRun<'_>>],
) -> Result<String> {
    let mut detail = CsvWriter::new(
        AtomicFile::create(&out.join("claims_variants.csv"))?,
        &["parameter", "value", "claim", "case", "verdict", "window"],
    )?;
    // Per claim: holds, transient, fails, not judged (a case's run failed at once).
    let mut counts = vec![[0usize; 4]; SPECS.len()];
    for ((what, value), cases) in variants.iter().zip(runs) {
        let judged = claims(cases);
        for (k, spec) in SPECS.iter().enumerate() {
            let Some(c) = judged.iter().find(|c| c.id == spec.id) else {
                counts[k][3] += 1;
                detail.write_record(&[what, value, spec.id, spec.case, "not_judged", ""])?;
                continue;
            };
            let column = match c.verdict {
                Verdict::Holds => 0,
                Verdict::Transient => 1,
                Verdict::Fails => 2,
            };
            counts[k][column] += 1;
            let window = c
                .window
                .map_or(String::new(), |w| format!("{} {}", w[0], w[1]));
            detail.write_record(&[what, value, spec.id, spec.case, c.verdict.name(), &window])?;
        }
    }
    detail.into_inner().commit()?;
    let mut csv = CsvWriter::new(
        AtomicFile::create(&out.join("claims_sensitivity.csv"))?,
        &[
            "claim",
            "case",
            "variants",
            "holds",
            "transient",
            "fails",
            "not_judged",
        ],
    )?;
    let line = |a: &str, b: &str, c: &str, d: &str, e: &str, f: &str| {
        format!("{a:<20} {b:>4} {c:>8} {d:>5} {e:>9} {f:>5}\n")
    };
    let mut table = line("claim", "case", "variants", "holds", "transient", "fails");
    for (spec, n) in SPECS.iter().zip(&counts) {
        let [holds, transient, fails, none] = n.map(|x| x.to_string());
        let total = variants.len().to_string();
        csv.write_record(&[
            spec.id, spec.case, &total, &holds, &transient, &fails, &none,
        ])?;
        table += &line(spec.id, spec.case, &total, &holds, &transient, &fails);
    }
    csv.into_inner().commit()?;
    Ok(table)
}
