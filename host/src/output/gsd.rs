//! GSD trajectories (HOOMD-blue's format, read by OVITO, freud, MDAnalysis and the
//! `gsd` Python package), written from the file-layer specification (version 2.0) and
//! the `hoomd` schema (version 1.4). No maintained Rust writer exists on crates.io.
//!
//! Layout, streamed with constant memory: a 256-byte header, then the data chunks frame
//! after frame, then (when the writer finishes) the index and the name list, and the
//! header rewritten to point at them. Every frame after the first holds the same
//! chunks, of the same sizes, so the index is computed from the frame count alone and a
//! file cut back to the end of a frame can be continued ([`GsdWriter::resume`]).
//!
//! Frame 0 holds the topology: particle count, type names and ids, masses, diameters,
//! bonds (one bond type, `rigid`). Every frame holds the time step number, the time
//! (`log/time`, f64), a box, and positions and velocities (f32, as the schema has
//! them; the extended XYZ trajectory has the exact f64 values). HOOMD's box is
//! periodic and centred on the origin. A run without a periodic cell gets, in each
//! frame, a box sized to enclose every sphere with room to spare (side `4 (max |x| +
//! max radius) + 1`), which keeps every bond shorter than half a side and so drawn
//! whole by viewers that apply the minimum image. A run in a periodic box
//! ([`Topology::cell`]) writes that box, positions wrapped into it (`[-L/2, L/2)` per
//! axis) and the chunk `particles/image` (int32, the whole box edges each position was
//! moved by), so that `position + image L` is the run's unwrapped position (to the f32
//! rounding of the wrapped one); its name list has `particles/image` at the end (id
//! 15), so a file without a cell is the same bytes as before boxes existed.

use std::io::{self, Seek, SeekFrom, Write};

use super::Topology;

const MAGIC: u64 = 0x65DF_65DF_65DF_65DF;
const HEADER_BYTES: u64 = 256;
const FILE_VERSION: u32 = 2 << 16;
const SCHEMA_VERSION: u32 = (1 << 16) | 4;
const NAME_SEGMENT: usize = 64;

// The file layer's type codes.
const UINT8: u8 = 1;
const UINT32: u8 = 3;
const UINT64: u8 = 4;
const INT8: u8 = 5;
const INT32: u8 = 7;
const FLOAT: u8 = 9;
const DOUBLE: u8 = 10;

/// The chunk names, in id order (the index is sorted by frame, then id); the last one
/// only in a file with a periodic cell.
const NAMES: [&str; 16] = [
    "bonds/N",
    "bonds/group",
    "bonds/typeid",
    "bonds/types",
    "configuration/box",
    "configuration/dimensions",
    "configuration/step",
    "log/time",
    "particles/N",
    "particles/diameter",
    "particles/mass",
    "particles/position",
    "particles/typeid",
    "particles/types",
    "particles/velocity",
    "particles/image",
];

/// Id of `particles/image`, written only with a periodic cell.
const IMAGE: usize = 15;

/// Ids of the chunks every frame holds.
const PER_FRAME: [usize; 6] = [4, 6, 7, 11, 14, IMAGE];

/// One chunk's shape: `n x m` elements of type `kind`.
#[derive(Clone, Copy)]
struct Shape {
    id: usize,
    n: u64,
    m: u32,
    kind: u8,
}

impl Shape {
    fn bytes(&self) -> u64 {
        let size = match self.kind {
            UINT8 | INT8 => 1,
            UINT32 | INT32 | FLOAT => 4,
            _ => 8,
        };
        self.n * u64::from(self.m) * size
    }
}

/// Writes a GSD trajectory of the particles a [`Topology`] describes.
pub struct GsdWriter<W: Write + Seek> {
    inner: W,
    topology: Topology,
    frames: u64,
}

fn names_width(names: &[String]) -> u32 {
    names.iter().map(|s| s.len() + 1).max().unwrap_or(1) as u32
}

impl<W: Write + Seek> GsdWriter<W> {
    /// Starts a file (the header, to be completed by [`finish`](Self::finish)).
    pub fn new(mut inner: W, topology: &Topology) -> io::Result<Self> {
        inner.write_all(&[0; HEADER_BYTES as usize])?;
        Ok(GsdWriter {
            inner,
            topology: topology.clone(),
            frames: 0,
        })
    }

    /// Continues a file cut back to [`data_end`](Self::data_end) after `frames` frames;
    /// `inner` stands at that end.
    pub fn resume(inner: W, topology: &Topology, frames: u64) -> Self {
        GsdWriter {
            inner,
            topology: topology.clone(),
            frames,
        }
    }

    /// Frames written.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Passes the frames written so far on to the file (a checkpoint names them).
    pub fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }

    /// The file as it stands, without its index (a stopped run continues it).
    pub fn into_inner(mut self) -> io::Result<W> {
        self.inner.flush()?;
        Ok(self.inner)
    }

    /// The chunks of frame `frame`, in id order.
    fn shapes(&self, frame: u64) -> Vec<Shape> {
        shapes(&self.topology, frame)
    }

    /// Bytes of frame `frame`'s data.
    fn frame_bytes(&self, frame: u64) -> u64 {
        frame_bytes(&self.topology, frame)
    }

    /// Where the data of `frames` frames ends (the header included).
    pub fn data_end(&self, frames: u64) -> u64 {
        data_end(&self.topology, frames)
    }
    /// Appends a frame at time step `step` and time `time`.
    pub fn write_frame(
        &mut self,
        step: u64,
        time: f64,
        positions: &[[f64; 3]],
        velocities: &[[f64; 3]],
    ) -> io::Result<()> {
        let t = &self.topology;
        let n = t.len();
        if positions.len() != n || velocities.len() != n {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "GSD frame of {} positions for {n} particles",
                    positions.len()
                ),
            ));
        }
        let mut buf = Vec::with_capacity(self.frame_bytes(self.frames) as usize);
        let u32s = |buf: &mut Vec<u8>, xs: &mut dyn Iterator<Item = u32>| {
            xs.for_each(|x| buf.extend_from_slice(&x.to_le_bytes()))
        };
        let f32s = |buf: &mut Vec<u8>, xs: &mut dyn Iterator<Item = f64>| {
            xs.for_each(|x| buf.extend_from_slice(&(x as f32).to_le_bytes()))
        };
        let names = |buf: &mut Vec<u8>, names: &[&str], width: u32| {
            for s in names {
                buf.extend_from_slice(s.as_bytes());
                buf.resize(buf.len() + width as usize - s.len(), 0);
            }
        };
        let vec3s = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<f64>>();
        // In a periodic cell: the box itself, positions wrapped into it, image flags.
        let (box_, positions, images) = match t.cell {
            None => (box_of(positions, &t.radius), positions.to_vec(), Vec::new()),
            Some(cell) => {
                let (p, i): (Vec<_>, Vec<_>) = positions.iter().map(|&p| wrap(cell, p)).unzip();
                ([cell[0], cell[1], cell[2], 0.0, 0.0, 0.0], p, i)
            }
        };
        for s in self.shapes(self.frames) {
            match s.id {
                0 => u32s(&mut buf, &mut std::iter::once(t.bonds.len() as u32)),
                1 => u32s(&mut buf, &mut t.bonds.iter().flatten().map(|&i| i as u32)),
                2 => u32s(&mut buf, &mut t.bonds.iter().map(|_| 0)),
                3 => names(&mut buf, &["rigid"], s.m),
                4 => f32s(&mut buf, &mut box_.into_iter()),
                5 => buf.push(3),
                6 => buf.extend_from_slice(&step.to_le_bytes()),
                7 => buf.extend_from_slice(&time.to_le_bytes()),
                8 => u32s(&mut buf, &mut std::iter::once(n as u32)),
                9 => f32s(&mut buf, &mut t.radius.iter().map(|r| 2.0 * r)),
                10 => f32s(&mut buf, &mut t.mass.iter().copied()),
                11 => f32s(&mut buf, &mut vec3s(&positions).into_iter()),
                12 => u32s(&mut buf, &mut t.typeid.iter().map(|&i| i as u32)),
                13 => {
                    let types: Vec<&str> = t.types.iter().map(String::as_str).collect();
                    names(&mut buf, &types, s.m)
                }
                14 => f32s(&mut buf, &mut vec3s(velocities).into_iter()),
                _ => images
                    .iter()
                    .flatten()
                    .for_each(|i| buf.extend_from_slice(&i.to_le_bytes())),
            }
        }
        self.inner.write_all(&buf)?;
        self.frames += 1;
        Ok(())
    }

    /// Writes the index and the name list after the data and completes the header;
    /// gives the writer back, standing at the end of the file.
    pub fn finish(mut self) -> io::Result<W> {
        let index_at = self.data_end(self.frames);
        let mut entries = 0u64;
        let mut at = HEADER_BYTES;
        let mut entry = Vec::with_capacity(32 * 16);
        for frame in 0..self.frames {
            entry.clear();
            for s in self.shapes(frame) {
                entry.extend_from_slice(&frame.to_le_bytes());
                entry.extend_from_slice(&s.n.to_le_bytes());
                entry.extend_from_slice(&at.to_le_bytes());
                entry.extend_from_slice(&s.m.to_le_bytes());
                entry.extend_from_slice(&(s.id as u16).to_le_bytes());
                entry.extend_from_slice(&[s.kind, 0]);
                at += s.bytes();
                entries += 1;
            }
            self.inner.write_all(&entry)?;
        }
        let count = if self.topology.cell.is_some() {
            IMAGE + 1
        } else {
            IMAGE
        };
        let mut names: Vec<u8> = NAMES[..count]
            .iter()
            .flat_map(|s| s.bytes().chain([0]))
            .collect();
        names.push(0);
        names.resize(names.len().div_ceil(NAME_SEGMENT) * NAME_SEGMENT, 0);
        let names_at = index_at + 32 * entries;
        self.inner.write_all(&names)?;
        let mut header = Vec::with_capacity(HEADER_BYTES as usize);
        for x in [
            MAGIC,
            index_at,
            entries,
            names_at,
            (names.len() / NAME_SEGMENT) as u64,
        ] {
            header.extend_from_slice(&x.to_le_bytes());
        }
        header.extend_from_slice(&SCHEMA_VERSION.to_le_bytes());
        header.extend_from_slice(&FILE_VERSION.to_le_bytes());
        for text in [crate::provenance::APPLICATION, "hoomd"] {
            let start = header.len();
            header.extend_from_slice(text.as_bytes());
            header.resize(start + 64, 0);
        }
        header.resize(HEADER_BYTES as usize, 0);
        self.inner.seek(SeekFrom::Start(0))?;
        self.inner.write_all(&header)?;
        self.inner.seek(SeekFrom::End(0))?;
        Ok(self.inner)
    }
}

/// The chunks of frame `frame`, in id order.
fn shapes(t: &Topology, frame: u64) -> Vec<Shape> {
    let (n, b) = (t.len() as u64, t.bonds.len() as u64);
    let shape = |id: usize, n: u64, m: u32, kind: u8| Shape { id, n, m, kind };
    let all = [
        shape(0, 1, 1, UINT32),
        shape(1, b, 2, UINT32),
        shape(2, b, 1, UINT32),
        shape(3, 1, "rigid".len() as u32 + 1, INT8),
        shape(4, 6, 1, FLOAT),
        shape(5, 1, 1, UINT8),
        shape(6, 1, 1, UINT64),
        shape(7, 1, 1, DOUBLE),
        shape(8, 1, 1, UINT32),
        shape(9, n, 1, FLOAT),
        shape(10, n, 1, FLOAT),
        shape(11, n, 3, FLOAT),
        shape(12, n, 1, UINT32),
        shape(13, t.types.len() as u64, names_width(&t.types), INT8),
        shape(14, n, 3, FLOAT),
        shape(IMAGE, n, 3, INT32),
    ];
    all.into_iter()
        .filter(|s| frame == 0 || PER_FRAME.contains(&s.id))
        .filter(|s| b > 0 || s.id > 3)
        .filter(|s| t.cell.is_some() || s.id != IMAGE)
        .collect()
}

/// Bytes of frame `frame`'s data.
fn frame_bytes(t: &Topology, frame: u64) -> u64 {
    shapes(t, frame).iter().map(Shape::bytes).sum()
}

/// Where the data of `frames` frames of the particles `t` describes ends (the header
/// included): the length to cut a file back to, to continue it after `frames` frames.
pub fn data_end(t: &Topology, frames: u64) -> u64 {
    match frames {
        0 => HEADER_BYTES,
        f => HEADER_BYTES + frame_bytes(t, 0) + (f - 1) * frame_bytes(t, 1),
    }
}

/// A position wrapped into the periodic box of edges `cell` centred on the origin, and
/// its image flags: per axis `w = p - n L` in `[-L/2, L/2)` in f32 as written (a `w`
/// that rounds to `L/2` belongs to the next image), `p = w + n L` to the rounding of
/// the subtraction.
fn wrap(cell: [f64; 3], p: [f64; 3]) -> ([f64; 3], [i32; 3]) {
    let mut w = [0.0; 3];
    let mut img = [0; 3];
    for k in 0..3 {
        let l = cell[k];
        let mut n = (p[k] / l + 0.5).floor();
        let mut x = p[k] - n * l;
        if x as f32 >= (0.5 * l) as f32 {
            n += 1.0;
            x -= l;
        }
        (w[k], img[k]) = (x, n as i32);
    }
    (w, img)
}

/// A box centred on the origin enclosing every sphere with room to spare.
fn box_of(positions: &[[f64; 3]], radius: &[f64]) -> [f64; 6] {
    let r = radius.iter().fold(0.0_f64, |a, &b| a.max(b));
    let mut side = [0.0; 3];
    for p in positions {
        for (s, x) in side.iter_mut().zip(p) {
            *s = f64::max(*s, x.abs());
        }
    }
    let side = side.map(|s| 4.0 * (s + r) + 1.0);
    [side[0], side[1], side[2], 0.0, 0.0, 0.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain() -> Topology {
        Topology {
            types: vec!["head".into(), "tail".into()],
            typeid: vec![0, 1, 1],
            radius: vec![1.26, 1.0, 1.0],
            mass: vec![37.7, 18.85, 18.85],
            bonds: vec![[0, 1], [1, 2]],
            cell: None,
        }
    }

    fn u64_at(bytes: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
    }

    #[test]
    fn header_index_and_names_point_at_each_other() {
        let mut w = GsdWriter::new(io::Cursor::new(Vec::new()), &chain()).unwrap();
        let p = [[0.0, 0.0, 0.0], [2.0, 0.0, 1.0], [4.0, 0.0, 2.0]];
        for k in 0..3 {
            w.write_frame(k, k as f64 * 0.5, &p, &p).unwrap();
        }
        assert_eq!(w.data_end(3), w.data_end(1) + 2 * w.frame_bytes(1));
        let end = w.data_end(3);
        let bytes = w.finish().unwrap().into_inner();
        assert_eq!(u64_at(&bytes, 0), MAGIC);
        assert_eq!(u64_at(&bytes, 8), end);
        let entries = u64_at(&bytes, 16);
        assert_eq!(entries, 15 + 2 * 5);
        let names_at = u64_at(&bytes, 24) as usize;
        assert_eq!(names_at as u64, end + 32 * entries);
        assert_eq!(bytes.len(), names_at + 64 * u64_at(&bytes, 32) as usize);
        assert!(bytes[names_at..].starts_with(b"bonds/N\0bonds/group\0"));
        assert_eq!(&bytes[48..53], b"hydro");
        assert_eq!(&bytes[112..117], b"hoomd");
        // The last index entry: frame 2, the velocities (id 14), right before the index.
        let last = end as usize + 32 * (entries as usize - 1);
        assert_eq!(u64_at(&bytes, last), 2);
        assert_eq!(u64_at(&bytes, last + 16), end - 3 * 3 * 4);
        assert_eq!(bytes[last + 28], 14);
    }
}
