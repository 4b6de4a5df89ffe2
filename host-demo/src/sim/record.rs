//! What a run records: a row of observables per frame, written to `observables.csv`
//! and, with the configuration, to `trajectory.xyz` and `trajectory.gsd`. Everything is
//! streamed: memory does not grow with the number of frames.

use std::io::Seek;
use std::path::Path;

use anyhow::{Context, Result};
use hydrorattle::observables;
use hydrorattle::{Bond, Real};
use serde::{Deserialize, Serialize};

use super::beads::Beads;
use crate::output::{AtomicFile, CsvWriter, Topology, XyzWriter, gsd::GsdWriter};

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

/// The files of a run, in the output folder.
pub const TRAJECTORY_XYZ: &str = "trajectory.xyz";
/// GSD trajectory.
pub const TRAJECTORY_GSD: &str = "trajectory.gsd";
/// Observables, one row per frame.
pub const OBSERVABLES_CSV: &str = "observables.csv";

/// One row of observables.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
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
    /// Constraint iterations of the step that led to this row (0 for the initial
    /// state and for a row closing a failed run).
    pub iterations: u32,
    /// Largest bond tension of the step that led to this row (0 likewise).
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

    /// Reads a row written by a run (bit-exact: numbers round-trip).
    pub fn from_row(line: &str) -> Option<Observables> {
        let x: Vec<f64> = line
            .split(',')
            .map(|f| f.parse().ok())
            .collect::<Option<_>>()?;
        (x.len() == COLUMNS.len()).then(|| Observables {
            time: x[0],
            extension: x[1],
            verticality: x[2],
            twist: x[3],
            head_z: x[4],
            head_speed: x[5],
            com: [x[6], x[7], x[8]],
            bond_residual: x[9],
            iterations: x[10] as u32,
            max_tension: x[11],
        })
    }
}

/// Where the files of a run stand: enough to cut them back to this point and continue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct Marks {
    /// Frames written.
    pub frames: u64,
    /// Bytes of `trajectory.xyz`.
    pub xyz_bytes: u64,
    /// Bytes of `observables.csv`.
    pub csv_bytes: u64,
}

/// The trajectory and observables files of a run (nothing when it writes no files).
pub(super) struct Recorder {
    files: Option<Files>,
    topology: Topology,
    frames: u64,
}

struct Files {
    xyz: XyzWriter<AtomicFile>,
    gsd: GsdWriter<AtomicFile>,
    csv: CsvWriter<AtomicFile>,
}

impl Recorder {
    /// Opens the files under `out`, if given: new ones, or (with `from`) the existing
    /// ones cut back to the marks of a checkpoint.
    pub(super) fn new(out: Option<&Path>, topology: Topology, from: Option<Marks>) -> Result<Self> {
        let Some(dir) = out else {
            return Ok(Recorder {
                files: None,
                topology,
                frames: 0,
            });
        };
        let (xyz, gsd, csv) = (
            dir.join(TRAJECTORY_XYZ),
            dir.join(TRAJECTORY_GSD),
            dir.join(OBSERVABLES_CSV),
        );
        let files = match from {
            None => Files {
                xyz: XyzWriter::new(AtomicFile::create(&xyz)?),
                gsd: GsdWriter::new(AtomicFile::create(&gsd)?, &topology)?,
                csv: CsvWriter::new(AtomicFile::create(&csv)?, &COLUMNS)?,
            },
            Some(m) => {
                let gsd_bytes = crate::output::gsd::data_end(&topology, m.frames);
                Files {
                    xyz: XyzWriter::new(AtomicFile::continue_from(&xyz, m.xyz_bytes)?),
                    gsd: GsdWriter::resume(
                        AtomicFile::continue_from(&gsd, gsd_bytes)?,
                        &topology,
                        m.frames,
                    ),
                    csv: CsvWriter::resume(
                        AtomicFile::continue_from(&csv, m.csv_bytes)?,
                        COLUMNS.len(),
                    ),
                }
            }
        };
        Ok(Recorder {
            files: Some(files),
            topology,
            frames: from.map_or(0, |m| m.frames),
        })
    }

    /// Writes one frame (reached at time step `step`) and its row.
    pub(super) fn record<T: Real>(
        &mut self,
        step: u64,
        beads: &Beads<T>,
        o: &Observables,
    ) -> Result<()> {
        self.frames += 1;
        let Some(f) = self.files.as_mut() else {
            return Ok(());
        };
        let f64s = |v: &[T::V3]| -> Vec<[f64; 3]> { v.iter().map(|&v| T::v3_to_f64(v)).collect() };
        let (pos, vel) = (f64s(&beads.pos), f64s(&beads.vel));
        f.xyz.write_frame(&self.topology, o.time, &pos, &vel)?;
        f.gsd.write_frame(step, o.time, &pos, &vel)?;
        f.csv.write_row(&o.row())?;
        Ok(())
    }

    /// Where the files stand now (flushed, so that a checkpoint can name the bytes).
    pub(super) fn marks(&mut self) -> Result<Marks> {
        let frames = self.frames;
        let Some(f) = self.files.as_mut() else {
            return Ok(Marks {
                frames,
                ..Marks::default()
            });
        };
        Ok(Marks {
            frames,
            xyz_bytes: f.xyz.get_mut().stream_position()?,
            csv_bytes: f.csv.get_mut().stream_position()?,
        })
    }

    /// Completes the GSD index and renames every file to its final name.
    pub(super) fn commit(self) -> Result<()> {
        if let Some(f) = self.files {
            f.xyz.into_inner().commit()?;
            f.gsd.finish()?.commit()?;
            f.csv.into_inner().commit()?;
        }
        Ok(())
    }
}

/// Calls `each` with every row of an `observables.csv` up to `bytes` (a checkpoint's
/// mark), in order, for a resumed run.
pub(super) fn each_row(path: &Path, bytes: u64, mut each: impl FnMut(Observables)) -> Result<()> {
    use std::io::{BufRead, Read};
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    let reader = std::io::BufReader::new(file.take(bytes));
    for (k, line) in reader.lines().enumerate().skip(1) {
        let line = line.with_context(|| format!("reading {}", path.display()))?;
        let o = Observables::from_row(&line)
            .with_context(|| format!("{}:{}: unreadable row", path.display(), k + 1))?;
        each(o);
    }
    Ok(())
}
