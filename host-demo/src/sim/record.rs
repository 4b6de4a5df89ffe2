//! What a run records: a row of observables per frame, written to `observables.csv`
//! and, with the configuration, to `trajectory.xyz`.

use std::path::Path;

use anyhow::Result;
use hydrorattle::observables;
use hydrorattle::{Bond, Real};
use serde::Serialize;

use super::beads::Beads;
use crate::output::{AtomicFile, CsvWriter, XyzWriter};

/// Columns of `observables.csv`, in order.
pub const COLUMNS: [&str; 12] = [
    "time",
    "extension",
    "verticality",
    "twist",
    "head_z",
    "head_speed",
    "com_x",
    "com_y",
    "com_z",
    "bond_residual",
    "iterations",
    "max_tension",
];

/// One row of observables.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Observables {
    /// Simulated time.
    pub time: f64,
    /// End-to-end distance over contour length.
    pub extension: f64,
    /// `|cos|` of the head-to-end vector with gravity.
    pub verticality: f64,
    /// Accumulated twist about the vertical through the head (radians).
    pub twist: f64,
    /// Head height.
    pub head_z: f64,
    /// Head settling speed (along gravity).
    pub head_speed: f64,
    /// Centre of mass.
    pub com: [f64; 3],
    /// Largest relative bond-length error.
    pub bond_residual: f64,
    /// Constraint iterations of the last step.
    pub iterations: u32,
    /// Largest bond tension of the last step.
    pub max_tension: f64,
}

impl Observables {
    /// The observables of `beads` (bead 0 is the head), with the twist so far and the
    /// last step's iterations and largest tension.
    pub fn of<T: Real>(
        beads: &Beads<T>,
        bonds: &[Bond<T>],
        gravity: T::V3,
        twist: T,
        iterations: u32,
        tension: T,
    ) -> Self {
        let pos = &beads.pos[..];
        let com = observables::centre_of_mass::<T>(pos, |i| beads.mass(i));
        Observables {
            time: beads.time.to_f64(),
            extension: observables::extension::<T>(pos, bonds).to_f64(),
            verticality: observables::verticality::<T>(pos, gravity).to_f64(),
            twist: twist.to_f64(),
            head_z: T::xyz(pos[0])[2].to_f64(),
            head_speed: observables::settling_speed::<T>(&beads.vel, 0, gravity).to_f64(),
            com: T::v3_to_f64(com),
            bond_residual: hydrorattle::bonds::max_residual(bonds, pos).1.to_f64(),
            iterations,
            max_tension: tension.to_f64(),
        }
    }

    fn row(&self) -> [f64; 12] {
        [
            self.time,
            self.extension,
            self.verticality,
            self.twist,
            self.head_z,
            self.head_speed,
            self.com[0],
            self.com[1],
            self.com[2],
            self.bond_residual,
            f64::from(self.iterations),
            self.max_tension,
        ]
    }
}

/// The trajectory and observables files of a run (nothing when it writes no files).
pub(super) struct Recorder {
    xyz: Option<XyzWriter<AtomicFile>>,
    csv: Option<CsvWriter<AtomicFile>>,
    species: Vec<&'static str>,
}

impl Recorder {
    /// Opens `trajectory.xyz` and `observables.csv` under `out`, if given.
    pub(super) fn new(out: Option<&Path>, species: Vec<&'static str>) -> Result<Self> {
        let (xyz, csv) = match out {
            Some(dir) => (
                Some(XyzWriter::new(AtomicFile::create(
                    &dir.join("trajectory.xyz"),
                )?)),
                Some(CsvWriter::new(
                    AtomicFile::create(&dir.join("observables.csv"))?,
                    &COLUMNS,
                )?),
            ),
            None => (None, None),
        };
        Ok(Recorder { xyz, csv, species })
    }

    /// Writes one frame and its row.
    pub(super) fn record<T: Real>(&mut self, beads: &Beads<T>, o: &Observables) -> Result<()> {
        if let Some(w) = self.xyz.as_mut() {
            let f64s =
                |v: &[T::V3]| -> Vec<[f64; 3]> { v.iter().map(|&v| T::v3_to_f64(v)).collect() };
            let rad: Vec<f64> = beads.radius.iter().map(|r| r.to_f64()).collect();
            w.write_frame(
                o.time,
                &self.species,
                &f64s(&beads.pos),
                &rad,
                &f64s(&beads.vel),
            )?;
        }
        if let Some(c) = self.csv.as_mut() {
            c.write_row(&o.row())?;
        }
        Ok(())
    }

    /// Renames both files to their final names.
    pub(super) fn commit(self) -> Result<()> {
        if let Some(w) = self.xyz {
            w.into_inner().commit()?;
        }
        if let Some(c) = self.csv {
            c.into_inner().commit()?;
        }
        Ok(())
    }
}
