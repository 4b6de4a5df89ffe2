//! What a run records: a row of observables per frame, written to `observables.csv`
//! and, with the configuration, to `trajectory.xyz` and `trajectory.gsd`. Everything is
//! streamed: memory does not grow with the number of frames.

use std::io::Seek;
use std::path::Path;

use anyhow::{Context, Result};
use hydrorattle::observables::{self, FrameState, Shape, StateThresholds, state_of};
use hydrorattle::{Bond, Real};
use serde::{Deserialize, Serialize};

use crate::output::{AtomicFile, CsvWriter, Topology, XyzWriter, format_f64, gsd::GsdWriter};
use crate::scene::Beads;

/// Columns of `observables.csv`, in order.
pub const COLUMNS: [&str; 24] = [
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
    "spin_rate",
    "spin_coherence",
    "poloidal_rate",
    "poloidal_coherence",
    "vertical_run",
    "horizontal_extent",
    "vertical_extent",
    "com_speed",
    "wall_height",
    "wall_gap",
    "wall_contacts",
    "state",
];

/// Numeric columns before the wall's (always written).
const NUMBERS: usize = 20;

/// A bond counts as near-vertical when the cosine of its angle with gravity is at least
/// this (within about 26 degrees of the vertical): the vertical runs and the stretching
/// front.
pub const NEAR_VERTICAL_COS: f64 = 0.9;

/// The files of a run, in the output folder.
pub const TRAJECTORY_XYZ: &str = "trajectory.xyz";
/// GSD trajectory.
pub const TRAJECTORY_GSD: &str = "trajectory.gsd";
/// Observables, one row per frame.
pub const OBSERVABLES_CSV: &str = "observables.csv";

/// A frame's named state ([`FrameState`]), written by its name; `other` by default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Label(pub FrameState);

impl Default for Label {
    fn default() -> Self {
        Label(FrameState::Other)
    }
}

impl Serialize for Label {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.name())
    }
}

impl<'de> Deserialize<'de> for Label {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        FrameState::from_name(&name)
            .map(Label)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown state {name:?}")))
    }
}

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
    /// Rotation rate about the vertical through the centre of mass (rad per time unit,
    /// right-handed about "up").
    pub spin_rate: f64,
    /// Share of the horizontal relative motion that rotation explains, in `[0, 1]`.
    pub spin_coherence: f64,
    /// Poloidal circulation rate (rolling over itself), rad per time unit.
    pub poloidal_rate: f64,
    /// Share of the relative motion that the poloidal circulation explains.
    pub poloidal_coherence: f64,
    /// Longest run of consecutive near-vertical bonds ([`NEAR_VERTICAL_COS`]).
    pub vertical_run: u32,
    /// Largest horizontal distance between two centres.
    pub horizontal_extent: f64,
    /// Spread of the centres' heights.
    pub vertical_extent: f64,
    /// Centre-of-mass settling speed (along gravity).
    pub com_speed: f64,
    /// With a wall: the centre of mass's height above it (empty in the CSV otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_height: Option<f64>,
    /// With a wall: the smallest gap between a sphere and the wall,
    /// `min_i (z_i - height - a_i)` (0 at contact).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_gap: Option<f64>,
    /// With a wall: the spheres in contact with it (gap within the kernel's contact
    /// tolerance, `2 tol a_i`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_contacts: Option<u32>,
    /// The frame's named state.
    pub state: Label,
}

/// The wall as the observables see it: the plane's height and the contact tolerance.
#[derive(Clone, Copy, Debug)]
pub(super) struct WallGauge<T> {
    /// The plane `z = height`.
    pub height: T,
    /// The solver's tolerance: a sphere within `2 tol a_i` of the wall touches it.
    pub tolerance: T,
}

impl<T: Real> WallGauge<T> {
    /// `(smallest gap, spheres in contact)` of `pos` with radii `radius`.
    pub(super) fn contact(&self, pos: &[T::V3], radius: &[T]) -> (f64, u32) {
        let (mut gap, mut touching) = (f64::INFINITY, 0);
        for (&r, &a) in pos.iter().zip(radius) {
            let g = T::xyz(r)[2] - self.height - a;
            gap = gap.min(g.to_f64());
            touching += u32::from(g <= a * self.tolerance * T::TWO);
        }
        (gap, touching)
    }
}

/// What [`Observables::of`] needs besides the state: the bonds, masses, gravity, and
/// the state thresholds.
pub(super) struct Observer<'a, T: Real> {
    /// Bonds in chain order.
    pub bonds: &'a [Bond<T>],
    /// Bead masses.
    pub mass: &'a [T],
    /// Gravitational acceleration.
    pub gravity: T::V3,
    /// Thresholds of the named states.
    pub thresholds: StateThresholds<T>,
    /// The wall, if any.
    pub wall: Option<WallGauge<T>>,
}

impl Observables {
    /// The observables of `beads` (bead 0 is the head), with the twist so far and the
    /// last step's iterations and largest tension.
    pub(super) fn of<T: Real>(
        beads: &Beads<T>,
        ob: &Observer<'_, T>,
        twist: T,
        iterations: u32,
        tension: T,
    ) -> Self {
        let (pos, vel, g) = (&beads.pos[..], &beads.vel[..], ob.gravity);
        let com = observables::centre_of_mass::<T>(pos, |i| beads.mass(i));
        let cos = T::from_f64(NEAR_VERTICAL_COS);
        let shape = Shape::measure(pos, vel, ob.mass, ob.bonds, g, cos);
        let wall = ob.wall.map(|w| (w.contact(pos, &beads.radius), w.height));
        Observables {
            time: beads.time.to_f64(),
            extension: shape.extension.to_f64(),
            verticality: shape.verticality.to_f64(),
            twist: twist.to_f64(),
            head_z: T::xyz(pos[0])[2].to_f64(),
            head_speed: observables::settling_speed::<T>(vel, 0, g).to_f64(),
            com: T::v3_to_f64(com),
            bond_residual: hydrorattle::bonds::max_residual(ob.bonds, pos).1.to_f64(),
            iterations,
            max_tension: tension.to_f64(),
            spin_rate: shape.spin.rate.to_f64(),
            spin_coherence: shape.spin.coherence.to_f64(),
            poloidal_rate: shape.poloidal.rate.to_f64(),
            poloidal_coherence: shape.poloidal.coherence.to_f64(),
            vertical_run: u32::try_from(shape.vertical_run).unwrap_or(u32::MAX),
            horizontal_extent: shape.horizontal.to_f64(),
            vertical_extent: shape.vertical.to_f64(),
            com_speed: observables::com_settling_speed::<T>(vel, ob.mass, g).to_f64(),
            wall_height: wall.map(|(_, h)| (T::xyz(com)[2] - h).to_f64()),
            wall_gap: wall.map(|((gap, _), _)| gap),
            wall_contacts: wall.map(|((_, n), _)| n),
            state: Label(state_of(&shape, &ob.thresholds)),
        }
    }

    /// The numeric columns before the wall's, in [`COLUMNS`] order.
    fn numbers(&self) -> [f64; NUMBERS] {
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
            self.spin_rate,
            self.spin_coherence,
            self.poloidal_rate,
            self.poloidal_coherence,
            f64::from(self.vertical_run),
            self.horizontal_extent,
            self.vertical_extent,
            self.com_speed,
        ]
    }

    /// The first column that is NaN or infinite, and its value: an observable the
    /// run's precision could not compute (squares of coordinates past its range).
    pub fn non_finite(&self) -> Option<(&'static str, f64)> {
        let wall = [self.wall_height, self.wall_gap].into_iter().flatten();
        let named = COLUMNS.iter().zip(self.numbers().into_iter().chain(wall));
        named.map(|(c, x)| (*c, x)).find(|(_, x)| !x.is_finite())
    }

    fn row(&self) -> Vec<String> {
        let mut row: Vec<String> = self.numbers().iter().map(|&x| format_f64(x)).collect();
        let or_empty = |x: Option<f64>| x.map_or(String::new(), format_f64);
        row.push(or_empty(self.wall_height));
        row.push(or_empty(self.wall_gap));
        row.push(or_empty(self.wall_contacts.map(f64::from)));
        row.push(self.state.0.name().to_string());
        row
    }

    /// Reads a row written by a run (bit-exact: numbers round-trip).
    pub fn from_row(line: &str) -> Option<Observables> {
        let fields: Vec<&str> = line.split(',').collect();
        (fields.len() == COLUMNS.len()).then_some(())?;
        let (state, numbers) = fields.split_last()?;
        let (numbers, wall) = numbers.split_at(NUMBERS);
        let x: Vec<f64> = numbers
            .iter()
            .map(|f| f.parse().ok())
            .collect::<Option<_>>()?;
        // Empty without a wall.
        let w: Vec<Option<f64>> = wall
            .iter()
            .map(|f| match f.is_empty() {
                true => Some(None),
                false => f.parse().ok().map(Some),
            })
            .collect::<Option<_>>()?;
        Some(Observables {
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
            spin_rate: x[12],
            spin_coherence: x[13],
            poloidal_rate: x[14],
            poloidal_coherence: x[15],
            vertical_run: x[16] as u32,
            horizontal_extent: x[17],
            vertical_extent: x[18],
            com_speed: x[19],
            wall_height: w[0],
            wall_gap: w[1],
            wall_contacts: w[2].map(|n| n as u32),
            state: Label(FrameState::from_name(state)?),
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
        f.csv.write_record(&o.row())?;
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
        // The GSD writer's buffer too: a run killed after this checkpoint must find
        // every frame the checkpoint counts in the file.
        f.gsd.flush()?;
        Ok(Marks {
            frames,
            xyz_bytes: f.xyz.get_mut().stream_position()?,
            csv_bytes: f.csv.get_mut().stream_position()?,
        })
    }

    /// Leaves every file under its temporary name, flushed (a run stopped on request:
    /// its checkpoint marks them).
    pub(super) fn suspend(self) -> Result<()> {
        if let Some(f) = self.files {
            f.xyz.into_inner().keep()?;
            f.gsd.into_inner()?.keep()?;
            f.csv.into_inner().keep()?;
        }
        Ok(())
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
