//! The one spelling of every choice a caller names: methods, hydrodynamic models,
//! solvers, noise square roots, drifts and failure stages.
//!
//! Scene files, the Python package, the C interface's documentation and the firmware's
//! summaries all read these tables, so a name is written once (here) and an unknown
//! one is refused with the same list of accepted names everywhere. The spellings are
//! the scene files' (kebab-case where a name has two words).

use core::fmt;

use crate::constraints::SolverKind;
use crate::error::Stage;
use crate::mobility::Hydro;
use crate::params::{Drift, Method, NoiseSqrt};

/// A name that none of a choice's values has. `Display` lists the accepted names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// What was being chosen (`"method"`, `"hydro"`, ...).
    pub what: &'static str,
    /// The accepted names, in the order of [`Named::ALL`].
    pub expected: &'static [&'static str],
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} must be one of ", self.what)?;
        for (k, name) in self.expected.iter().enumerate() {
            let sep = match k {
                0 => "",
                _ if k + 1 == self.expected.len() => " or ",
                _ => ", ",
            };
            write!(f, "{sep}\"{name}\"")?;
        }
        Ok(())
    }
}

impl core::error::Error for UnknownName {}

/// A choice with a fixed set of named values (implemented by every enum of this
/// module's tables), for front ends that parse or print any of them the same way.
pub trait Named: Copy + Sized + 'static {
    /// What the choice is called (`"method"`, ...): the scene key's usual name.
    const WHAT: &'static str;
    /// Every value, the default first, in the order scene files' errors list them.
    const ALL: &'static [Self];
    /// Every value's name, in the order of [`Named::ALL`].
    const NAMES: &'static [&'static str];

    /// The value's name.
    fn name(self) -> &'static str;

    /// The value called `name` (exact spelling), or [`UnknownName`].
    fn from_name(name: &str) -> Result<Self, UnknownName> {
        Self::NAMES
            .iter()
            .position(|n| *n == name)
            .and_then(|k| Self::ALL.get(k).copied())
            .ok_or(UnknownName {
                what: Self::WHAT,
                expected: Self::NAMES,
            })
    }
}

/// One table per enum: the inherent `const fn name`, `ALL`, `NAMES` and `from_name`,
/// and the [`Named`] impl, all from the same `Variant => "name"` list.
macro_rules! names {
    ($ty:ident, $what:literal, [$($variant:ident => $name:literal),+ $(,)?]) => {
        impl $ty {
            #[doc = concat!("Every `", stringify!($ty), "`, the default first, in the order errors list them.")]
            pub const ALL: &'static [Self] = &[$(Self::$variant),+];
            #[doc = concat!("The names of [`", stringify!($ty), "::ALL`], in its order.")]
            pub const NAMES: &'static [&'static str] = &[$($name),+];

            /// The name scene files, Python and the firmware's summaries use.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Self::$variant => $name),+
                }
            }

            /// The value called `name` (exact spelling), or [`UnknownName`] listing
            /// the accepted names.
            pub fn from_name(name: &str) -> Result<Self, UnknownName> {
                <Self as Named>::from_name(name)
            }
        }

        impl Named for $ty {
            const WHAT: &'static str = $what;
            const ALL: &'static [Self] = $ty::ALL;
            const NAMES: &'static [&'static str] = $ty::NAMES;

            fn name(self) -> &'static str {
                $ty::name(self)
            }
        }
    };
}

names!(Method, "method", [
    Overdamped => "overdamped",
    Overdamped2 => "overdamped2",
    Rattle => "rattle",
    RattleStable => "rattle-stable",
    Springs => "springs",
]);

names!(Hydro, "hydro", [
    Rpy => "rpy",
    Oseen => "oseen",
    FreeDraining => "free-draining",
]);

names!(SolverKind, "solver", [
    Auto => "auto",
    Sweep => "sweep",
    Newton => "newton",
    Krylov => "krylov",
]);

names!(NoiseSqrt, "sqrt", [
    Auto => "auto",
    Cholesky => "cholesky",
    Lanczos => "lanczos",
]);

names!(Drift, "drift", [
    Midpoint => "midpoint",
    Uncorrected => "uncorrected",
]);

names!(Stage, "stage", [
    Mobility => "mobility",
    Drag => "drag",
    Positions => "positions",
    Velocities => "velocities",
    Stability => "stability",
    Contacts => "contacts",
]);

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<T: Named + PartialEq + fmt::Debug>() {
        assert_eq!(T::ALL.len(), T::NAMES.len());
        for (&v, &n) in T::ALL.iter().zip(T::NAMES) {
            assert_eq!(v.name(), n);
            assert_eq!(T::from_name(n), Ok(v));
            // Names are exact: no case folding, no trimming.
            let mut upper = [0u8; 32];
            let upper = &mut upper[..n.len()];
            upper.copy_from_slice(n.as_bytes());
            upper.make_ascii_uppercase();
            // ASCII names stay UTF-8 when upper-cased; a name that did not would fail.
            let upper = core::str::from_utf8(upper);
            assert!(upper.is_ok_and(|u| T::from_name(u).is_err()), "{upper:?}");
        }
        let e = T::from_name("").err().map(|e| (e.what, e.expected));
        assert_eq!(e, Some((T::WHAT, T::NAMES)));
    }

    #[test]
    fn every_name_round_trips() {
        round_trip::<Method>();
        round_trip::<Hydro>();
        round_trip::<SolverKind>();
        round_trip::<NoiseSqrt>();
        round_trip::<Drift>();
        round_trip::<Stage>();
    }

    #[test]
    fn the_scene_files_spellings() {
        // Existing scene files and outputs name these; they must never change.
        assert_eq!(
            Method::NAMES,
            [
                "overdamped",
                "overdamped2",
                "rattle",
                "rattle-stable",
                "springs"
            ]
        );
        assert_eq!(Hydro::NAMES, ["rpy", "oseen", "free-draining"]);
        assert_eq!(SolverKind::NAMES, ["auto", "sweep", "newton", "krylov"]);
        assert_eq!(NoiseSqrt::NAMES, ["auto", "cholesky", "lanczos"]);
        assert_eq!(Drift::NAMES, ["midpoint", "uncorrected"]);
    }

    #[test]
    fn an_unknown_name_lists_the_accepted_ones() -> core::fmt::Result {
        use core::fmt::Write;
        let mut s = heapless::String::<128>::new();
        // An accepted name would print nothing, and fail the comparison.
        if let Err(e) = Drift::from_name("ito") {
            write!(s, "{e}")?;
        }
        assert_eq!(s, "drift must be one of \"midpoint\" or \"uncorrected\"");
        s.clear();
        if let Err(e) = NoiseSqrt::from_name("x") {
            write!(s, "{e}")?;
        }
        assert_eq!(
            s,
            "sqrt must be one of \"auto\", \"cholesky\" or \"lanczos\""
        );
        Ok(())
    }
}
