//! Output files: atomic writes, extended XYZ trajectories (writer and reader), GSD
//! trajectories, CSV and JSON.
//!
//! Every file goes first to `NAME.tmp` in its final directory, is flushed and synced to
//! disk, and only then renamed to `NAME`: a crash leaves at most a `.tmp` file, never a
//! half-written file under the final name.
//!
//! Numbers are written with [`format_f64`], the shortest decimal that parses back to
//! the same `f64`, so a trajectory read back with [`read_xyz`] is bit-exact.

mod atomic;
mod csv;
mod digest;
pub mod gsd;
mod lock;
mod xyz;

pub use atomic::{AtomicFile, continued_source, name_error, tmp_path, write_atomic, write_json};
pub use csv::{CsvWriter, csv_field, csv_fields};
pub use digest::{FileCheck, check_files, fnv1a64, mismatch};
pub use lock::{FolderLock, LOCK_FILE, Locked};
pub use xyz::{Frame, XYZ_PROPERTIES, XyzError, XyzWriter, read_xyz, read_xyz_file};

/// What stays the same from frame to frame of a trajectory: particle types, radii,
/// masses and bonds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Topology {
    /// Type names (non-empty, no whitespace), indexed by [`typeid`](Self::typeid).
    pub types: Vec<String>,
    /// Type of each particle.
    pub typeid: Vec<usize>,
    /// Radius of each particle.
    pub radius: Vec<f64>,
    /// Mass of each particle.
    pub mass: Vec<f64>,
    /// Bonded pairs.
    pub bonds: Vec<[usize; 2]>,
    /// The periodic box's edges `Lx, Ly, Lz`, when the run has one: the trajectories
    /// give it (GSD `configuration/box` and `particles/image`, extended XYZ
    /// `Lattice=`).
    pub cell: Option<[f64; 3]>,
}

impl Topology {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.typeid.len()
    }

    /// `true` with no particles.
    pub fn is_empty(&self) -> bool {
        self.typeid.is_empty()
    }

    /// The type name of each particle.
    pub fn species(&self) -> Vec<&str> {
        self.typeid
            .iter()
            .map(|&t| self.types[t].as_str())
            .collect()
    }
}

/// The shortest decimal text that parses back to exactly `x`: plain notation for
/// magnitudes in `[1e-5, 1e16)` and for zero, scientific (`1.5e-7`) otherwise;
/// `NaN`, `inf` and `-inf` for the non-finite values.
pub fn format_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "hydrorattle-host-output-{}-{name}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn format_round_trips() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1.0 / 3.0,
            -2.5e-300,
            1e-5,
            9.99e-6,
            1e16,
            6.02214076e23,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let text = format_f64(x);
            let back: f64 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x} -> {text}");
            assert!(text.len() < 30, "{text}");
        }
        assert_eq!(format_f64(1.5), "1.5");
        assert_eq!(format_f64(1.5e-7), "1.5e-7");
        assert!(format_f64(f64::NAN).parse::<f64>().unwrap().is_nan());
    }

    #[test]
    fn atomic_write_leaves_no_tmp_and_replaces() {
        let dir = scratch("atomic");
        let path = dir.join("a.json");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "second");
        assert!(!tmp_path(&path).exists());
        assert_eq!(tmp_path(&path), dir.join("a.json.tmp"));
    }

    #[test]
    fn uncommitted_file_never_appears() {
        let dir = scratch("uncommitted");
        let path = dir.join("t.xyz");
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.write_all(b"half a frame").unwrap();
            assert!(tmp_path(&path).exists());
            assert!(!path.exists());
        }
        assert!(!path.exists());
        assert!(!tmp_path(&path).exists());
    }

    #[test]
    fn json_is_pretty_and_atomic() {
        let dir = scratch("json");
        let path = dir.join("s.json");
        write_json(&path, &serde_json::json!({"steps": 3})).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.ends_with("}\n"));
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["steps"], 3);
    }
}
