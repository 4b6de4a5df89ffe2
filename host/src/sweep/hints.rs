//! Misspelled sweep tables and settings, said at their line with what was meant: a
//! `[sweeep]` table (which the scene reader would take for an unknown scene table, or
//! leave the file without a sweep), `[[sweep.zipp]]`, `replica = 3`.

use std::ops::Range;

use toml::de::{DeTable, DeValue};

use super::file::{Source, in_file_order};
use crate::scene::SceneError;

/// The settings of `[sweep]` that are not scene keys.
const SETTINGS: [&str; 3] = ["base", "replicas", "zip"];

/// Levenshtein distance (case-insensitive), for names a typo away.
fn distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (
        a.to_lowercase().chars().collect(),
        b.to_lowercase().chars().collect(),
    );
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let here = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != cb)).min(row[j] + 1).min(here + 1);
            prev = here;
        }
    }
    row[b.len()]
}

/// A name one or two edits from `target` (and not it).
fn near(name: &str, target: &str) -> bool {
    name != target && distance(name, target) <= 2.min(target.len() / 2)
}

/// Where a file has no `[sweep]` table: a top-level table named nearly so, at its line.
pub(super) fn missing_sweep(src: &Source<'_>, doc: &DeTable<'_>) -> Option<SceneError> {
    let (key, _) = in_file_order(doc)
        .into_iter()
        .find(|(k, _)| near(k.get_ref(), "sweep"))?;
    Some(src.err(
        key.span(),
        format!(
            "[{}] is not a table a sweep file has: did you mean [sweep]? (without [sweep] this is no sweep)",
            key.get_ref()
        ),
    ))
}

/// A key of `[sweep]` that is no dotted scene key and a typo away from a setting
/// (`replica`, `zipp`, `bases`), or a list of tables other than `zip`: at its line.
pub(super) fn misspelled_setting(
    src: &Source<'_>,
    name: &str,
    span: Range<usize>,
    value: &DeValue<'_>,
) -> Option<SceneError> {
    if name.contains('.') {
        return None;
    }
    let tables = matches!(value, DeValue::Array(a) if a.iter().next().is_some_and(|g| matches!(g.get_ref(), DeValue::Table(_))));
    let meant = SETTINGS.iter().find(|s| near(name, s));
    let message = match (meant, tables) {
        (Some(&"zip"), _) | (None, true) => format!(
            "[[sweep.{name}]] is not a sweep table: did you mean [[sweep.zip]] (keys that vary together)?"
        ),
        (Some(s), _) => format!(
            "{name:?} is not a sweep setting: did you mean {s}? (a sweep sets base, replicas and [[sweep.zip]]; scene keys are dotted and quoted, as \"helix.dhat\")"
        ),
        (None, false) => return None,
    };
    Some(src.err(span, message))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_typo_away() {
        assert_eq!(distance("sweeep", "sweep"), 1);
        assert_eq!(distance("replica", "replicas"), 1);
        assert!(near("zipp", "zip") && near("Sweep", "sweep") && !near("sweep", "sweep"));
        assert!(!near("gravity", "zip") && !near("dt", "zip"));
    }
}
