//! The scene files' names of the kernel's choices come from the kernel's tables
//! ([`hydrorattle::names`]): each scene enum is read and written through its kernel
//! value's name, so the files, Python and the firmware spell a choice one way.
//!
//! The scene enums stay (they carry the scene's documentation and defaults); only
//! their spellings moved. An unknown name is refused with serde's own
//! `unknown variant` message listing the kernel's names, as the derived code did.

use std::fmt;
use std::marker::PhantomData;

use hydrorattle::Named;
use serde::de::{self, Visitor};

/// A scene enum that stands for a kernel choice `K`, one variant each.
pub(crate) trait Kernel: Copy + 'static {
    /// The kernel's choice.
    type K: Named + PartialEq;
    /// Every variant.
    const ALL: &'static [Self];
    /// The kernel's value.
    fn kernel(self) -> Self::K;
}

/// Reads a scene enum from its kernel name.
pub(crate) fn deserialize<'de, D, H>(d: D) -> Result<H, D::Error>
where
    D: de::Deserializer<'de>,
    H: Kernel,
{
    struct Name<H>(PhantomData<H>);
    impl<H: Kernel> Visitor<'_> for Name<H> {
        type Value = H;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "a {} name", H::K::WHAT)
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<H, E> {
            let k = H::K::from_name(v).map_err(|_| E::unknown_variant(v, H::K::NAMES))?;
            // Every kernel value has its scene variant (a test checks it).
            H::ALL
                .iter()
                .copied()
                .find(|h| h.kernel() == k)
                .ok_or_else(|| E::unknown_variant(v, H::K::NAMES))
        }
    }
    d.deserialize_str(Name(PhantomData))
}

/// `Serialize` and `Deserialize` of a [`Kernel`] scene enum by the kernel's names.
macro_rules! by_kernel_name {
    ($ty:ty) => {
        impl serde::Serialize for $ty {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(hydrorattle::Named::name(
                    $crate::scene::names::Kernel::kernel(*self),
                ))
            }
        }
        impl<'de> serde::Deserialize<'de> for $ty {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $crate::scene::names::deserialize(d)
            }
        }
    };
}
pub(crate) use by_kernel_name;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Drift, Hydrodynamics, Method, Solver, Sqrt};

    /// Each scene enum and its kernel choice are one to one, and read back what they write.
    fn one_to_one<H>()
    where
        H: Kernel + PartialEq + fmt::Debug + serde::Serialize + for<'de> serde::Deserialize<'de>,
    {
        assert_eq!(H::ALL.len(), H::K::ALL.len());
        for &k in H::K::ALL {
            assert_eq!(H::ALL.iter().filter(|h| h.kernel() == k).count(), 1);
        }
        for &h in H::ALL {
            let json = serde_json::to_string(&h).unwrap();
            assert_eq!(json, format!("\"{}\"", h.kernel().name()));
            assert_eq!(serde_json::from_str::<H>(&json).unwrap(), h);
        }
        let e = serde_json::from_str::<H>("\"nope\"")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("unknown variant `nope`, expected "), "{e}");
    }

    #[test]
    fn scene_names_are_the_kernels() {
        one_to_one::<Method>();
        one_to_one::<Hydrodynamics>();
        one_to_one::<Solver>();
        one_to_one::<Drift>();
        one_to_one::<Sqrt>();
    }
}
