//! Output files: atomic writes, extended XYZ trajectories (writer and reader), CSV and
//! JSON.
//!
//! Every file goes first to `NAME.tmp` in its final directory, is flushed and synced to
//! disk, and only then renamed to `NAME`: a crash leaves at most a `.tmp` file, never a
//! half-written file under the final name.
//!
//! Numbers are written with [`format_f64`], the shortest decimal that parses back to
//! the same `f64`, so a trajectory read back with [`read_xyz`] is bit-exact.

use serde::Serialize;
use std::fmt;
use std::fs::File;
use std::io::{self, BufRead, BufWriter, Write};
use std::path::{Path, PathBuf};

/// The extended XYZ `Properties` value of the trajectories this module writes.
pub const XYZ_PROPERTIES: &str = "species:S:1:pos:R:3:radius:R:1:velocity:R:3";

// ---------------------------------------------------------------------------------------
// Atomic files
// ---------------------------------------------------------------------------------------

/// The temporary name a file is written under before it is renamed: `NAME.tmp` in the
/// same directory.
pub fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// A file being written under its temporary name; [`AtomicFile::commit`] makes it
/// appear under its final name. Dropped without a commit, the temporary file is
/// removed.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    writer: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Creates (truncates) `NAME.tmp` next to `path`.
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        let tmp = tmp_path(path);
        let file = File::create(&tmp)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            writer: Some(BufWriter::new(file)),
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs the data to disk and renames the file to its final name (then
    /// syncs the directory, where the platform allows it).
    pub fn commit(mut self) -> io::Result<()> {
        let writer = self
            .writer
            .take()
            .expect("an uncommitted file has a writer");
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&self.tmp, &self.path)?;
        sync_parent(&self.path);
        Ok(())
    }

    fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer
            .as_mut()
            .expect("an uncommitted file has a writer")
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.writer().write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> io::Result<()> {
        self.writer().write_all(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.writer().flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Best-effort sync of the directory holding `path`, so that a rename survives a crash.
fn sync_parent(path: &Path) {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if let Ok(dir) = File::open(parent) {
        let _ = dir.sync_all();
    }
}

/// Writes `bytes` to `path` atomically (temporary name, sync, rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

/// Writes `value` as pretty-printed JSON (with a final newline), atomically.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(io::Error::other)?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

// ---------------------------------------------------------------------------------------
// Numbers
// ---------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------
// Extended XYZ
// ---------------------------------------------------------------------------------------

/// One trajectory frame, as read back by [`read_xyz`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frame {
    /// Simulated time (the comment line's `Time`).
    pub time: f64,
    /// Species name of each particle.
    pub species: Vec<String>,
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
    /// Velocities.
    pub velocities: Vec<[f64; 3]>,
}

/// Writes frames in extended XYZ, one after another, with no periodic cell:
///
/// ```text
/// 2
/// Properties=species:S:1:pos:R:3:radius:R:1:velocity:R:3 Time=0.5 pbc="F F F"
/// H 0 0 0 1.2599210498948732 0 0 -1
/// Ta 2 0 1.7 1 0 0 -1
/// ```
pub struct XyzWriter<W: Write> {
    inner: W,
}

impl<W: Write> XyzWriter<W> {
    /// Wraps a writer (buffer it, e.g. an [`AtomicFile`]).
    pub fn new(inner: W) -> Self {
        XyzWriter { inner }
    }

    /// Writes one frame. All slices must have the same length; species names must be
    /// non-empty and free of whitespace.
    pub fn write_frame<S: AsRef<str>>(
        &mut self,
        time: f64,
        species: &[S],
        positions: &[[f64; 3]],
        radii: &[f64],
        velocities: &[[f64; 3]],
    ) -> io::Result<()> {
        let n = positions.len();
        if species.len() != n || radii.len() != n || velocities.len() != n {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "frame arrays differ in length: {} species, {n} positions, {} radii, {} velocities",
                    species.len(),
                    radii.len(),
                    velocities.len()
                ),
            ));
        }
        if let Some(bad) = species
            .iter()
            .map(AsRef::as_ref)
            .find(|s| s.is_empty() || s.contains(char::is_whitespace))
        {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("species name {bad:?} is empty or contains whitespace"),
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
        writeln!(
            w,
            "Properties={XYZ_PROPERTIES} Time={time_text} pbc=\"F F F\""
        )?;
        for k in 0..n {
            let (p, v) = (positions[k], velocities[k]);
            writeln!(
                w,
                "{} {} {} {} {} {} {} {}",
                species[k].as_ref(),
                format_f64(p[0]),
                format_f64(p[1]),
                format_f64(p[2]),
                format_f64(radii[k]),
                format_f64(v[0]),
                format_f64(v[1]),
                format_f64(v[2]),
            )?;
        }
        Ok(())
    }

    /// Writes a [`Frame`].
    pub fn write(&mut self, frame: &Frame) -> io::Result<()> {
        self.write_frame(
            frame.time,
            &frame.species,
            &frame.positions,
            &frame.radii,
            &frame.velocities,
        )
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }

    /// Gives the underlying writer back (to commit an [`AtomicFile`], say).
    pub fn into_inner(self) -> W {
        self.inner
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
    velocity: usize,
    total: usize,
}

fn columns(properties: &str) -> Result<Columns, String> {
    let parts: Vec<&str> = properties.split(':').collect();
    if parts.len() % 3 != 0 {
        return Err(format!(
            "Properties={properties} is not name:type:count triples"
        ));
    }
    let (mut species, mut pos, mut radius, mut velocity) = (None, None, None, None);
    let mut at = 0;
    for t in parts.chunks(3) {
        let count: usize = t[2]
            .parse()
            .map_err(|_| format!("bad column count {:?} in Properties", t[2]))?;
        let slot = match (t[0], t[1], count) {
            ("species", "S", 1) => Some(&mut species),
            ("pos", "R", 3) => Some(&mut pos),
            ("radius", "R", 1) => Some(&mut radius),
            ("velocity", "R", 3) => Some(&mut velocity),
            ("species" | "pos" | "radius" | "velocity", ..) => {
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
        velocity: need(velocity, "velocity")?,
        total: at,
    })
}

/// Reads every frame of an extended XYZ stream that has (at least) the columns
/// species, pos, radius and velocity and a `Time` in each comment line.
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
        let mut frame = Frame {
            time,
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

// ---------------------------------------------------------------------------------------
// CSV
// ---------------------------------------------------------------------------------------

/// Writes comma-separated values with a header row. Numbers use [`format_f64`]; text
/// fields are quoted when they contain a comma, a quote or a line break.
pub struct CsvWriter<W: Write> {
    inner: W,
    columns: usize,
}

/// Quotes a CSV field when needed.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

impl<W: Write> CsvWriter<W> {
    /// Writes the header row.
    pub fn new<S: AsRef<str>>(mut inner: W, columns: &[S]) -> io::Result<Self> {
        let header: Vec<String> = columns.iter().map(|c| csv_field(c.as_ref())).collect();
        writeln!(inner, "{}", header.join(","))?;
        Ok(CsvWriter {
            inner,
            columns: columns.len(),
        })
    }

    fn check(&self, len: usize) -> io::Result<()> {
        if len == self.columns {
            Ok(())
        } else {
            Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("CSV row has {len} fields, the header {}", self.columns),
            ))
        }
    }

    /// Writes a row of numbers.
    pub fn write_row(&mut self, values: &[f64]) -> io::Result<()> {
        self.check(values.len())?;
        let row: Vec<String> = values.iter().map(|&v| format_f64(v)).collect();
        writeln!(self.inner, "{}", row.join(","))
    }

    /// Writes a row of already formatted fields (quoted as needed), for mixed rows.
    pub fn write_record<S: AsRef<str>>(&mut self, fields: &[S]) -> io::Result<()> {
        self.check(fields.len())?;
        let row: Vec<String> = fields.iter().map(|f| csv_field(f.as_ref())).collect();
        writeln!(self.inner, "{}", row.join(","))
    }

    /// Gives the underlying writer back.
    pub fn into_inner(self) -> W {
        self.inner
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("host-demo-output-{}-{name}", std::process::id()));
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

    #[test]
    fn reader_reports_the_line_of_a_short_frame() {
        let text = format!("2\nProperties={XYZ_PROPERTIES} Time=0\nH 0 0 0 1 0 0 0\n");
        let e = read_xyz(text.as_bytes()).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
    }

    #[test]
    fn writer_rejects_mismatched_arrays() {
        let mut w = XyzWriter::new(Vec::new());
        let e = w
            .write_frame(0.0, &["H"], &[[0.0; 3]; 2], &[1.0; 2], &[[0.0; 3]; 2])
            .unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert!(
            w.write_frame(0.0, &["a b"], &[[0.0; 3]], &[1.0], &[[0.0; 3]])
                .is_err()
        );
    }

    #[test]
    fn csv_quotes_and_counts() {
        let mut w = CsvWriter::new(Vec::new(), &["time", "outcome"]).unwrap();
        w.write_record(&["1.5", "twisting, late"]).unwrap();
        assert!(w.write_row(&[1.0]).is_err());
        let text = String::from_utf8(w.into_inner()).unwrap();
        assert_eq!(text, "time,outcome\n1.5,\"twisting, late\"\n");
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
