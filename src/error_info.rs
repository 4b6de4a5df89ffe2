//! The errors' parts as plain values: a stable snake_case kind per variant (nested
//! errors included), the stage, the indices and the numbers they carry.
//!
//! Front ends (Python's exception attributes, the C interface's report, the firmware's
//! summary line) read these instead of each flattening the variants itself, so a new
//! variant is described once, here. Kinds never change once published; the parts are
//! `None` where a variant has none.

use crate::error::{BondError, LinalgError, ParticleError, Stage, StepError};

impl ParticleError {
    /// Stable snake_case name of the variant (`"bad_radius"`, ...).
    pub const fn kind(&self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::NonFinite { .. } => "non_finite",
            Self::BadRadius { .. } => "bad_radius",
            Self::BadDensity { .. } => "bad_density",
            Self::Nested { .. } => "nested",
            Self::Coincident { .. } => "coincident",
            Self::Overlap { .. } => "overlap",
            Self::Massless { .. } => "massless",
            Self::BelowWall { .. } => "below_wall",
            Self::Unresolved { .. } => "unresolved",
        }
    }

    /// The particle at fault (the first of a pair).
    pub const fn index(&self) -> Option<usize> {
        match *self {
            Self::Full => None,
            Self::NonFinite { particle }
            | Self::BadRadius { particle }
            | Self::BadDensity { particle }
            | Self::Massless { particle }
            | Self::BelowWall { particle }
            | Self::Unresolved { particle } => Some(particle),
            Self::Nested { i, .. } | Self::Coincident { i, .. } | Self::Overlap { i, .. } => {
                Some(i)
            }
        }
    }

    /// The two particles of a nesting or an overlap.
    pub const fn pair(&self) -> Option<(usize, usize)> {
        match *self {
            Self::Nested { i, j } | Self::Coincident { i, j } | Self::Overlap { i, j } => {
                Some((i, j))
            }
            _ => None,
        }
    }
}

impl BondError {
    /// Stable snake_case name of the variant (`"bad_length"`, ...).
    pub const fn kind(&self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::SelfBond { .. } => "self_bond",
            Self::OutOfRange { .. } => "out_of_range",
            Self::Duplicate { .. } => "duplicate",
            Self::BadLength { .. } => "bad_length",
            Self::Violated { .. } => "violated",
            Self::Overstretched { .. } => "overstretched",
            Self::BadTree { .. } => "bad_tree",
        }
    }

    /// The bond at fault, or for [`BondError::BadTree`] the child particle.
    pub const fn index(&self) -> Option<usize> {
        match *self {
            Self::Full => None,
            Self::SelfBond { bond, .. }
            | Self::OutOfRange { bond, .. }
            | Self::Duplicate { bond, .. }
            | Self::BadLength { bond }
            | Self::Violated { bond, .. }
            | Self::Overstretched { bond, .. } => Some(bond),
            Self::BadTree { particle } => Some(particle),
        }
    }

    /// The second index the error names: the particle a bond names wrongly
    /// (`SelfBond`, `OutOfRange`) or the earlier bond a duplicate repeats.
    pub const fn other(&self) -> Option<usize> {
        match *self {
            Self::SelfBond { particle, .. } | Self::OutOfRange { particle, .. } => Some(particle),
            Self::Duplicate { other, .. } => Some(other),
            _ => None,
        }
    }

    /// The relative length error (`Violated`) or the length over the maximum extension
    /// (`Overstretched`).
    pub const fn value(&self) -> Option<f64> {
        match *self {
            Self::Violated { residual, .. } => Some(residual),
            Self::Overstretched { ratio, .. } => Some(ratio),
            _ => None,
        }
    }
}

impl LinalgError {
    /// Stable snake_case name of the variant.
    pub const fn kind(&self) -> &'static str {
        match self {
            Self::NotPositiveDefinite { .. } => "not_positive_definite",
            Self::Singular { .. } => "singular",
        }
    }

    /// The scalar row whose pivot failed.
    pub const fn row(&self) -> usize {
        match *self {
            Self::NotPositiveDefinite { row } | Self::Singular { row } => row,
        }
    }
}

impl StepError {
    /// Stable snake_case name of the variant, a nested error's joined on with `_`:
    /// `"no_convergence"`, `"particle_bad_radius"`, `"bond_violated"`,
    /// `"linalg_not_positive_definite"`, ...
    pub const fn kind(&self) -> &'static str {
        match self {
            Self::BadTimeStep => "bad_time_step",
            Self::BadParameter(_) => "bad_parameter",
            Self::Particle(e) => match e {
                ParticleError::Full => "particle_full",
                ParticleError::NonFinite { .. } => "particle_non_finite",
                ParticleError::BadRadius { .. } => "particle_bad_radius",
                ParticleError::BadDensity { .. } => "particle_bad_density",
                ParticleError::Nested { .. } => "particle_nested",
                ParticleError::Coincident { .. } => "particle_coincident",
                ParticleError::Overlap { .. } => "particle_overlap",
                ParticleError::Massless { .. } => "particle_massless",
                ParticleError::BelowWall { .. } => "particle_below_wall",
                ParticleError::Unresolved { .. } => "particle_unresolved",
            },
            Self::Bond(e) => match e {
                BondError::Full => "bond_full",
                BondError::SelfBond { .. } => "bond_self_bond",
                BondError::OutOfRange { .. } => "bond_out_of_range",
                BondError::Duplicate { .. } => "bond_duplicate",
                BondError::BadLength { .. } => "bond_bad_length",
                BondError::Violated { .. } => "bond_violated",
                BondError::Overstretched { .. } => "bond_overstretched",
                BondError::BadTree { .. } => "bond_bad_tree",
            },
            Self::Linalg { error, .. } => match error {
                LinalgError::NotPositiveDefinite { .. } => "linalg_not_positive_definite",
                LinalgError::Singular { .. } => "linalg_singular",
            },
            Self::NoConvergence { .. } => "no_convergence",
            Self::Degenerate { .. } => "degenerate",
            Self::Infeasible { .. } => "infeasible",
            Self::NonFinite { .. } => "non_finite",
            Self::NonFiniteForce { .. } => "non_finite_force",
            Self::Overlap { .. } => "overlap",
            Self::Storage { .. } => "storage",
            Self::StateLength => "state_length",
            Self::Unstable { .. } => "unstable",
            Self::ContactsFull { .. } => "contacts_full",
            Self::Unsupported(_) => "unsupported",
        }
    }

    /// What a `BadParameter` names (the parameter) or an `Unsupported` names (the
    /// combination).
    pub const fn detail(&self) -> Option<&'static str> {
        match *self {
            Self::BadParameter(what) | Self::Unsupported(what) => Some(what),
            _ => None,
        }
    }

    /// The stage of a factorisation failure or of a solve that did not converge.
    pub const fn stage(&self) -> Option<Stage> {
        match *self {
            Self::Linalg { stage, .. } | Self::NoConvergence { stage, .. } => Some(stage),
            _ => None,
        }
    }

    /// The particle, bond or scalar row at fault (the first particle of a pair; a
    /// contact past the bonds for `Degenerate`, as it documents).
    pub const fn index(&self) -> Option<usize> {
        match *self {
            Self::Particle(e) => e.index(),
            Self::Bond(e) => e.index(),
            Self::Linalg { error, .. } => Some(error.row()),
            Self::Degenerate { bond, .. } => Some(bond),
            Self::Infeasible { constraints, .. } => Some(constraints[0]),
            Self::NonFinite { particle } | Self::NonFiniteForce { particle } => Some(particle),
            Self::Overlap { i, .. } => Some(i),
            _ => None,
        }
    }

    /// The second index an error names: the other particle of a pair, the particle a
    /// bond names wrongly, the earlier bond a duplicate repeats.
    pub const fn other(&self) -> Option<usize> {
        match *self {
            Self::Particle(e) => match e.pair() {
                Some((_, j)) => Some(j),
                None => None,
            },
            Self::Bond(e) => e.other(),
            Self::Overlap { j, .. } => Some(j),
            Self::Infeasible {
                constraints, shown, ..
            } if shown > 1 => Some(constraints[1]),
            _ => None,
        }
    }

    /// The two particles of an overlap or a nesting.
    pub const fn pair(&self) -> Option<(usize, usize)> {
        match *self {
            Self::Particle(e) => e.pair(),
            Self::Overlap { i, j } => Some((i, j)),
            _ => None,
        }
    }

    /// Every constraint an `Infeasible` lists (empty for the others).
    pub fn constraints(&self) -> &[usize] {
        match self {
            Self::Infeasible {
                constraints, shown, ..
            } => &constraints[..*shown],
            _ => &[],
        }
    }

    /// A count the error carries: the iterations done (`NoConvergence`), the contact
    /// capacity (`ContactsFull`) or the size of an infeasible dependent set
    /// (`Infeasible`).
    pub const fn count(&self) -> Option<usize> {
        match *self {
            Self::NoConvergence { iterations, .. } => Some(iterations as usize),
            Self::Infeasible { count, .. } => Some(count),
            Self::ContactsFull { capacity } => Some(capacity),
            _ => None,
        }
    }

    /// The number at fault: the residual left (`NoConvergence`, `Bond(Violated)`), the
    /// length ratio (`Bond(Overstretched)`), the time step refused (`Unstable`).
    pub const fn value(&self) -> Option<f64> {
        match *self {
            Self::Bond(e) => e.value(),
            Self::NoConvergence { residual, .. } => Some(residual),
            Self::Unstable { dt, .. } => Some(dt),
            _ => None,
        }
    }

    /// The stability limit an `Unstable` step exceeded.
    pub const fn limit(&self) -> Option<f64> {
        match *self {
            Self::Unstable { limit, .. } => Some(limit),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Layout;

    /// One of every variant (nested ones included).
    fn every() -> [StepError; 34] {
        let p = |e| StepError::Particle(e);
        let b = |e| StepError::Bond(e);
        let (i, j, bond) = (3, 5, 7);
        let lin = |error| StepError::Linalg {
            stage: Stage::Drag,
            error,
        };
        [
            StepError::BadTimeStep,
            StepError::BadParameter("tolerance"),
            p(ParticleError::Full),
            p(ParticleError::NonFinite { particle: i }),
            p(ParticleError::BadRadius { particle: i }),
            p(ParticleError::BadDensity { particle: i }),
            p(ParticleError::Nested { i, j }),
            p(ParticleError::Coincident { i, j }),
            p(ParticleError::Overlap { i, j }),
            p(ParticleError::Massless { particle: i }),
            p(ParticleError::BelowWall { particle: i }),
            p(ParticleError::Unresolved { particle: i }),
            b(BondError::Full),
            b(BondError::SelfBond { bond, particle: i }),
            b(BondError::OutOfRange { bond, particle: j }),
            b(BondError::Duplicate { bond, other: 2 }),
            b(BondError::BadLength { bond }),
            b(BondError::Violated {
                bond,
                residual: 0.5,
            }),
            b(BondError::Overstretched { bond, ratio: 1.5 }),
            b(BondError::BadTree { particle: i }),
            lin(LinalgError::NotPositiveDefinite { row: 11 }),
            lin(LinalgError::Singular { row: 11 }),
            StepError::NoConvergence {
                stage: Stage::Positions,
                iterations: 100,
                residual: 1e-3,
            },
            StepError::Degenerate {
                bond,
                row: crate::error::Row::Bond(bond),
            },
            StepError::NonFinite { particle: i },
            StepError::NonFiniteForce { particle: i },
            StepError::Overlap { i, j },
            StepError::Storage {
                need: Layout::default(),
                have: Layout::default(),
            },
            StepError::StateLength,
            StepError::Unstable {
                dt: 0.1,
                limit: 0.05,
            },
            StepError::ContactsFull { capacity: 9 },
            StepError::Infeasible {
                constraints: [2, 5, 7, 0],
                shown: 3,
                count: 6,
            },
            StepError::Unsupported("noise"),
            StepError::Particle(ParticleError::Full),
        ]
    }

    #[test]
    fn kinds_are_distinct_snake_case_and_the_nested_ones_are_prefixed() {
        let all = every();
        // The last entry repeats one to check that equal errors share a kind.
        let (all, repeat) = all.split_at(all.len() - 1);
        assert_eq!(repeat[0].kind(), "particle_full");
        for (k, a) in all.iter().enumerate() {
            let kind = a.kind();
            assert!(
                kind.bytes().all(|c| c.is_ascii_lowercase() || c == b'_'),
                "{kind}"
            );
            for b in &all[k + 1..] {
                assert_ne!(kind, b.kind());
            }
            let nested = match a {
                StepError::Particle(e) => Some(("particle_", e.kind())),
                StepError::Bond(e) => Some(("bond_", e.kind())),
                StepError::Linalg { error, .. } => Some(("linalg_", error.kind())),
                _ => None,
            };
            if let Some((prefix, inner)) = nested {
                assert_eq!(kind.strip_prefix(prefix), Some(inner));
            }
        }
    }

    #[test]
    fn the_parts_are_the_payloads() -> Result<(), &'static str> {
        let all = every();
        // A kind missing from `every` is that kind, as the error.
        let at = |kind: &'static str| all.iter().find(|e| e.kind() == kind).copied().ok_or(kind);
        let e = at("particle_overlap")?;
        assert_eq!(
            (e.index(), e.other(), e.pair()),
            (Some(3), Some(5), Some((3, 5)))
        );
        let e = at("bond_self_bond")?;
        assert_eq!((e.index(), e.other(), e.pair()), (Some(7), Some(3), None));
        assert_eq!(at("bond_duplicate")?.other(), Some(2));
        assert_eq!(at("bond_violated")?.value(), Some(0.5));
        assert_eq!(at("bond_overstretched")?.value(), Some(1.5));
        assert_eq!(at("bond_bad_tree")?.index(), Some(3));
        let e = at("linalg_singular")?;
        assert_eq!((e.stage(), e.index()), (Some(Stage::Drag), Some(11)));
        let e = at("no_convergence")?;
        assert_eq!(
            (e.stage(), e.count(), e.value()),
            (Some(Stage::Positions), Some(100), Some(1e-3))
        );
        let e = at("unstable")?;
        assert_eq!((e.value(), e.limit()), (Some(0.1), Some(0.05)));
        assert_eq!(at("contacts_full")?.count(), Some(9));
        let e = at("infeasible")?;
        assert_eq!(
            (e.index(), e.other(), e.count(), e.constraints()),
            (Some(2), Some(5), Some(6), &[2, 5, 7][..])
        );
        assert_eq!(at("overlap")?.pair(), Some((3, 5)));
        assert_eq!(at("bad_parameter")?.detail(), Some("tolerance"));
        assert_eq!(at("unsupported")?.detail(), Some("noise"));
        for kind in [
            "bad_time_step",
            "storage",
            "state_length",
            "particle_full",
            "bond_full",
        ] {
            let e = at(kind)?;
            assert_eq!(
                (
                    e.stage(),
                    e.index(),
                    e.other(),
                    e.count(),
                    e.value(),
                    e.limit()
                ),
                (None, None, None, None, None, None),
                "{kind}"
            );
        }
        Ok(())
    }
}
