//! Scene files name the kernel's choices by the kernel's tables
//! ([`hydrorattle::names`]): the scene holds the kernel's enums themselves
//! ([`hydrorattle::Method`], [`hydrorattle::Hydro`], [`hydrorattle::SolverKind`],
//! [`hydrorattle::Drift`], [`hydrorattle::NoiseSqrt`]), so a choice has one definition
//! and one spelling in files, Python and the firmware.
//!
//! The kernel links no serde; this module reads and writes any [`Named`] choice for
//! serde. An unknown name is refused with serde's own `unknown variant` message listing
//! the kernel's names.

use std::fmt;
use std::marker::PhantomData;

use hydrorattle::Named;
use serde::de::{self, Visitor};

/// A kernel choice read from its name (`Deserialize` for the scene's raw tables).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Name<K>(pub K);

impl<'de, K: Named> serde::Deserialize<'de> for Name<K> {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Of<K>(PhantomData<K>);
        impl<K: Named> Visitor<'_> for Of<K> {
            type Value = Name<K>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "a {} name", K::WHAT)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Name<K>, E> {
                K::from_name(v)
                    .map(Name)
                    .map_err(|_| E::unknown_variant(v, K::NAMES))
            }
        }
        d.deserialize_str(Of(PhantomData))
    }
}

/// Writes a kernel choice as its name: `#[serde(serialize_with =
/// "hydrorattle_host::scene::names::serialize")]` on a field of a kernel enum.
pub fn serialize<K: Named, S: serde::Serializer>(k: &K, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(k.name())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Drift, Hydrodynamics, Method, Solver, Sqrt};

    #[derive(serde::Serialize)]
    struct Out<K: Named>(#[serde(serialize_with = "serialize")] K);

    /// Each kernel choice reads back what it writes, and refuses an unknown name with
    /// the list of the kernel's names.
    fn round_trip<K: Named + PartialEq + fmt::Debug>() {
        for &k in K::ALL {
            let json = serde_json::to_string(&Out(k)).unwrap();
            assert_eq!(json, format!("\"{}\"", k.name()));
            assert_eq!(serde_json::from_str::<Name<K>>(&json).unwrap(), Name(k));
        }
        let e = serde_json::from_str::<Name<K>>("\"nope\"")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("unknown variant `nope`, expected "), "{e}");
        for n in K::NAMES {
            assert!(e.contains(&format!("`{n}`")), "{e} lacks {n}");
        }
    }

    /// The scene holds the kernel's enums themselves, not copies converted by hand.
    #[test]
    fn scene_choices_are_the_kernels_enums() {
        use std::any::TypeId;
        assert_eq!(TypeId::of::<Method>(), TypeId::of::<hydrorattle::Method>());
        assert_eq!(
            TypeId::of::<Hydrodynamics>(),
            TypeId::of::<hydrorattle::Hydro>()
        );
        assert_eq!(
            TypeId::of::<Solver>(),
            TypeId::of::<hydrorattle::SolverKind>()
        );
        assert_eq!(TypeId::of::<Drift>(), TypeId::of::<hydrorattle::Drift>());
        assert_eq!(TypeId::of::<Sqrt>(), TypeId::of::<hydrorattle::NoiseSqrt>());
    }

    /// A scene file's unknown name is refused with every accepted name, in the
    /// kernel's order and spelling.
    #[test]
    fn unknown_names_list_the_accepted_ones() {
        let od = "[integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1\n";
        let kt = "[brownian]\ntemperature = 1\n";
        let cases = [
            (
                "[integrator]\nmethod = \"verlet\"\ndt = 0.01\nduration = 1\n".to_string(),
                "unknown variant `verlet`, expected one of `overdamped`, `overdamped2`, \
                 `rattle`, `rattle-stable`, `springs`",
            ),
            (
                format!("{od}solver = \"lu\"\n"),
                "unknown variant `lu`, expected one of `auto`, `sweep`, `newton`, `krylov`",
            ),
            (
                format!("{od}[model]\nhydrodynamics = \"stokes\"\n"),
                "unknown variant `stokes`, expected one of `rpy`, `oseen`, `free-draining`",
            ),
            (
                format!("{od}{kt}drift = \"ito\"\n"),
                "unknown variant `ito`, expected `midpoint` or `uncorrected`",
            ),
            (
                format!("{od}{kt}sqrt = \"qr\"\n"),
                "unknown variant `qr`, expected one of `auto`, `cholesky`, `lanczos`",
            ),
        ];
        for (tail, message) in cases {
            let text = format!("[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n{tail}");
            let e = crate::scene::Scene::parse(&text, "s.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains(message), "{e}");
        }
    }

    #[test]
    fn scene_names_are_the_kernels() {
        round_trip::<Method>();
        round_trip::<Hydrodynamics>();
        round_trip::<Solver>();
        round_trip::<Drift>();
        round_trip::<Sqrt>();
    }
}
