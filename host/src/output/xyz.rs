//! Extended XYZ trajectories: writer and reader.
//!
//! Each particle line carries, in order: `species` (the particle's type name: OVITO's
//! Particle Type), `pos`, `Z` (the 1-based type number: ASE builds its atoms from it,
//! so type names need not be chemical symbols), `radius`, `mass` (OVITO's Mass),
//! `masses` (ASE's `get_masses()`), `velo` (OVITO's Velocity, exact) and `momenta` (mass
//! times velocity: ASE's `get_velocities()` divides it by the masses). The two mass
//! columns are the same numbers under each reader's name.

use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, Write};
use std::path::Path;

use super::{Topology, format_f64};

/// The extended XYZ `Properties` value of the trajectories this module writes.
pub const XYZ_PROPERTIES: &str =
    "species:S:1:pos:R:3:Z:I:1:radius:R:1:mass:R:1:masses:R:1:velo:R:3:momenta:R:3";

/// One trajectory frame, as read back by [`read_xyz`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frame {
    /// Simulated time (the comment line's `Time`).
    pub time: f64,
    /// Type name of each particle.
    pub species: Vec<String>,
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
    /// Masses (empty when the file has no mass column).
    pub masses: Vec<f64>,
    /// Velocities.
    pub velocities: Vec<[f64; 3]>,
    /// The periodic cell's edges, from an orthorhombic `Lattice` (`None` without one).
    pub cell: Option<[f64; 3]>,
}

/// Writes frames in extended XYZ, one after another; with no periodic cell
/// (`pbc="F F F"`), or with the [`Topology::cell`] as `Lattice="Lx 0 0 0 Ly 0 0 0 Lz"`
/// and `pbc="T T T"`, positions unwrapped (as the run holds them: ASE's and OVITO's
/// positions are then continuous, MSDs direct):
///
/// ```text
/// 2
/// Properties=species:S:1:pos:R:3:Z:I:1:radius:R:1:mass:R:1:masses:R:1:velo:R:3:momenta:R:3 Time=0.5 pbc="F F F"
/// head 0 0 0 1 1.2599210498948732 37.69911184307752 37.69911184307752 0 0 -1 0 0 -37.69911184307752
/// tail 2 0 1.7 2 1 18.84955592153876 18.84955592153876 0 0 -1 0 0 -18.84955592153876
/// ```
pub struct XyzWriter<W: Write> {
    inner: W,
}

impl<W: Write> XyzWriter<W> {
    /// Wraps a writer (buffer it, e.g. an [`AtomicFile`](super::AtomicFile)).
    pub fn new(inner: W) -> Self {
        XyzWriter { inner }
    }

    /// Writes one frame of the particles `topology` describes.
    pub fn write_frame(
        &mut self,
        topology: &Topology,
        time: f64,
        positions: &[[f64; 3]],
        velocities: &[[f64; 3]],
    ) -> io::Result<()> {
        let n = topology.len();
        if positions.len() != n || velocities.len() != n {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "frame of {} positions and {} velocities for {n} particles",
                    positions.len(),
                    velocities.len()
                ),
            ));
        }
        let w = &mut self.inner;
        writeln!(w, "{n}")?;
        // Time always reads as a real number (`0.0`, not `0`), so that readers that
        // guess types from the text (ASE) type it the same in every frame.
        let mut time_text = format_f64(time);
        if !time_text.contains(['.', 'e', 'N', 'n']) {
            time_text.push_str(".0");
        }
        match topology.cell {
            None => writeln!(
                w,
                "Properties={XYZ_PROPERTIES} Time={time_text} pbc=\"F F F\""
            )?,
            // The periodic cell, positions unwrapped (ASE and OVITO read both).
            Some([lx, ly, lz]) => {
                let [lx, ly, lz] = [lx, ly, lz].map(format_f64);
                writeln!(
                    w,
                    "Lattice=\"{lx} 0 0 0 {ly} 0 0 0 {lz}\" Properties={XYZ_PROPERTIES} Time={time_text} pbc=\"T T T\""
                )?
            }
        }
        for k in 0..n {
            let (p, v, m) = (positions[k], velocities[k], topology.mass[k]);
            let t = topology.typeid[k];
            let mut line = String::with_capacity(200);
            line.push_str(&topology.types[t]);
            for x in [p[0], p[1], p[2]] {
                line.push(' ');
                line.push_str(&format_f64(x));
            }
            line.push_str(&format!(" {}", t + 1));
            for x in [
                topology.radius[k],
                m,
                m,
                v[0],
                v[1],
                v[2],
                m * v[0],
                m * v[1],
                m * v[2],
            ] {
                line.push(' ');
                line.push_str(&format_f64(x));
            }
            writeln!(w, "{line}")?;
        }
        Ok(())
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }

    /// Gives the underlying writer back (to commit an [`AtomicFile`](super::AtomicFile),
    /// say).
    pub fn into_inner(self) -> W {
        self.inner
    }

    /// The underlying writer.
    pub fn get_mut(&mut self) -> &mut W {
        &mut self.inner
    }
}

/// A malformed extended XYZ file.
#[derive(Debug)]
pub struct XyzError {
    /// 1-based line number (0 when the error is not tied to a line).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for XyzError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for XyzError {}

fn xyz_error(line: usize, message: impl Into<String>) -> XyzError {
    XyzError {
        line,
        message: message.into(),
    }
}

/// Splits an extended XYZ comment line into `key=value` pairs; values may be quoted
/// with double quotes (`pbc="F F F"`).
fn comment_pairs(line: &str) -> Result<Vec<(String, String)>, String> {
    let mut pairs = Vec::new();
    let mut chars = line.trim().chars().peekable();
    loop {
        while chars.next_if(|c| c.is_whitespace()).is_some() {}
        if chars.peek().is_none() {
            return Ok(pairs);
        }
        let mut key = String::new();
        while let Some(c) = chars.next_if(|&c| c != '=' && !c.is_whitespace()) {
            key.push(c);
        }
        if chars.next_if_eq(&'=').is_none() {
            // A bare key is a true flag in extended XYZ.
            pairs.push((key, "T".to_string()));
            continue;
        }
        let mut value = String::new();
        if chars.next_if_eq(&'"').is_some() {
            loop {
                match chars.next() {
                    Some('"') => break,
                    Some(c) => value.push(c),
                    None => return Err(format!("unterminated quote in the value of {key}")),
                }
            }
        } else {
            while let Some(c) = chars.next_if(|c| !c.is_whitespace()) {
                value.push(c);
            }
        }
        pairs.push((key, value));
    }
}

/// Where each needed quantity sits among a line's whitespace-separated columns.
struct Columns {
    species: usize,
    pos: usize,
    radius: usize,
    mass: Option<usize>,
    velocity: usize,
    total: usize,
}

fn columns(properties: &str) -> Result<Columns, String> {
    let parts: Vec<&str> = properties.split(':').collect();
    if !parts.len().is_multiple_of(3) {
        return Err(format!(
            "Properties={properties} is not name:type:count triples"
        ));
    }
    let (mut species, mut pos, mut radius, mut velocity) = (None, None, None, None);
    let mut mass = None;
    let mut at = 0;
    for t in parts.chunks(3) {
        let count: usize = t[2]
            .parse()
            .map_err(|_| format!("bad column count {:?} in Properties", t[2]))?;
        let slot = match (t[0], t[1], count) {
            ("species", "S", 1) => Some(&mut species),
            ("pos", "R", 3) => Some(&mut pos),
            ("radius", "R", 1) => Some(&mut radius),
            ("velo" | "velocity", "R", 3) => Some(&mut velocity),
            ("mass", "R", 1) => Some(&mut mass),
            ("species" | "pos" | "radius" | "velo" | "velocity" | "mass", ..) => {
                return Err(format!("unexpected type or count for {}", t[0]));
            }
            _ => None,
        };
        if let Some(slot) = slot {
            *slot = Some(at);
        }
        at += count;
    }
    let need = |v: Option<usize>, name: &str| v.ok_or_else(|| format!("Properties lacks {name}"));
    Ok(Columns {
        species: need(species, "species")?,
        pos: need(pos, "pos")?,
        radius: need(radius, "radius")?,
        mass,
        velocity: need(velocity, "velo")?,
        total: at,
    })
}

/// The edges of an orthorhombic `Lattice` (nine numbers, zero off the diagonal).
fn lattice(text: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|t| t.parse().ok())
        .collect::<Option<_>>()?;
    let diagonal = v.len() == 9 && [1, 2, 3, 5, 6, 7].iter().all(|&k| v[k] == 0.0);
    diagonal.then(|| [v[0], v[4], v[8]])
}

/// Reads every frame of an extended XYZ stream that has (at least) the columns
/// species, pos, radius and velo (or velocity) and a `Time` in each comment line.
pub fn read_xyz<R: BufRead>(reader: R) -> Result<Vec<Frame>, XyzError> {
    let mut lines = reader.lines().enumerate().map(|(i, l)| (i + 1, l));
    let mut next = |what: &str| -> Result<Option<(usize, String)>, XyzError> {
        match lines.next() {
            None => Ok(None),
            Some((no, Ok(text))) => Ok(Some((no, text))),
            Some((no, Err(e))) => Err(xyz_error(no, format!("cannot read {what}: {e}"))),
        }
    };
    let mut frames = Vec::new();
    loop {
        let Some((no, count_line)) = next("a frame header")? else {
            return Ok(frames);
        };
        if count_line.trim().is_empty() {
            continue;
        }
        let n: usize = count_line
            .trim()
            .parse()
            .map_err(|_| xyz_error(no, format!("expected a particle count, got {count_line:?}")))?;
        let (no, comment) =
            next("a comment line")?.ok_or_else(|| xyz_error(no + 1, "missing comment line"))?;
        let pairs = comment_pairs(&comment).map_err(|m| xyz_error(no, m))?;
        let value = |key: &str| {
            pairs
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case(key))
                .map(|(_, v)| v.as_str())
        };
        let cols = columns(value("Properties").ok_or_else(|| xyz_error(no, "no Properties"))?)
            .map_err(|m| xyz_error(no, m))?;
        let time_text = value("Time").ok_or_else(|| xyz_error(no, "no Time"))?;
        let time = time_text
            .parse()
            .map_err(|_| xyz_error(no, format!("bad Time {time_text:?}")))?;
        let cell = value("Lattice")
            .map(|l| lattice(l).ok_or_else(|| xyz_error(no, format!("bad Lattice {l:?}"))))
            .transpose()?;
        let mut frame = Frame {
            time,
            cell,
            ..Frame::default()
        };
        for k in 0..n {
            let (no, line) = next("a particle line")?.ok_or_else(|| {
                xyz_error(no + 1 + k, format!("frame ends after {k} of {n} particles"))
            })?;
            let fields: Vec<&str> = line.split_whitespace().collect();
            if fields.len() != cols.total {
                return Err(xyz_error(
                    no,
                    format!("expected {} columns, found {}", cols.total, fields.len()),
                ));
            }
            let real = |i: usize| -> Result<f64, XyzError> {
                fields[i]
                    .parse()
                    .map_err(|_| xyz_error(no, format!("bad number {:?}", fields[i])))
            };
            let vec3 = |i: usize| -> Result<[f64; 3], XyzError> {
                Ok([real(i)?, real(i + 1)?, real(i + 2)?])
            };
            frame.species.push(fields[cols.species].to_string());
            frame.positions.push(vec3(cols.pos)?);
            frame.radii.push(real(cols.radius)?);
            if let Some(m) = cols.mass {
                frame.masses.push(real(m)?);
            }
            frame.velocities.push(vec3(cols.velocity)?);
        }
        frames.push(frame);
    }
}

/// Reads an extended XYZ file (see [`read_xyz`]); errors name the path.
pub fn read_xyz_file(path: &Path) -> anyhow::Result<Vec<Frame>> {
    let file = File::open(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    read_xyz(io::BufReader::new(file)).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comment_line_parses_quoted_values() {
        let pairs = comment_pairs(r#"Properties=a:R:1 Time=2.5 pbc="F F F" flag"#).unwrap();
        assert_eq!(pairs[2], ("pbc".into(), "F F F".into()));
        assert_eq!(pairs[3], ("flag".into(), "T".into()));
    }

    #[test]
    fn reader_accepts_extra_columns_in_any_order() {
        let text = "1\nTime=1 Properties=pos:R:3:id:I:1:velocity:R:3:radius:R:1:species:S:1\n\
                    1 2 3 7 4 5 6 0.5 X\n";
        let frames = read_xyz(text.as_bytes()).unwrap();
        assert_eq!(frames[0].species, vec!["X"]);
        assert_eq!(frames[0].positions, vec![[1.0, 2.0, 3.0]]);
        assert_eq!(frames[0].velocities, vec![[4.0, 5.0, 6.0]]);
        assert_eq!(frames[0].radii, vec![0.5]);
    }

    fn two() -> Topology {
        Topology {
            types: vec!["head".into(), "tail".into()],
            typeid: vec![0, 1],
            radius: vec![1.5, 1.0],
            mass: vec![2.0, 4.0],
            bonds: vec![[0, 1]],
            cell: None,
        }
    }

    #[test]
    fn reader_reports_the_line_of_a_short_frame() {
        let mut w = XyzWriter::new(Vec::new());
        w.write_frame(&two(), 0.0, &[[0.0; 3]; 2], &[[0.0; 3]; 2])
            .unwrap();
        let mut text = String::from_utf8(w.into_inner()).unwrap();
        text.truncate(text.trim_end().rfind('\n').unwrap() + 1);
        let e = read_xyz(text.as_bytes()).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
    }

    #[test]
    fn a_frame_reads_back_with_types_masses_and_velocities() {
        let mut w = XyzWriter::new(Vec::new());
        let v = [[0.0, 0.1, -1.0], [1.0 / 3.0, 0.0, 0.0]];
        w.write_frame(&two(), 0.0, &[[0.0; 3], [0.0, 0.0, 2.5]], &v)
            .unwrap();
        let text = String::from_utf8(w.into_inner()).unwrap();
        assert!(text.contains("Time=0.0 "), "{text}");
        let f = read_xyz(text.as_bytes()).unwrap().remove(0);
        assert_eq!(f.species, vec!["head", "tail"]);
        assert_eq!(f.masses, vec![2.0, 4.0]);
        assert_eq!(f.radii, vec![1.5, 1.0]);
        assert_eq!(f.velocities, v);
    }

    #[test]
    fn writer_rejects_mismatched_arrays() {
        let mut w = XyzWriter::new(Vec::new());
        let e = w
            .write_frame(&two(), 0.0, &[[0.0; 3]; 3], &[[0.0; 3]; 2])
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
    }
}
