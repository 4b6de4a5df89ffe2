//! The product-path model: which way of applying the mobility is fastest for a bead
//! count and a thread count (docs/BENCHMARKS.md, "Every core and every lane").
//!
//! A pass over the pairs moves `bytes` per pair to or from memory and does `ns` of one
//! core's work per pair. On `t` threads it takes `max(bytes / bw(t), ns / t)` per pair,
//! with `bw(t) = min(t b1, b)`: one thread moves `b1` bytes per ns, the machine `b` at
//! most. An Overdamped step ([`Machine::step`]) is one assembly pass, `k` products and
//! a serial rest that no thread count shortens. The assembly pass evaluates every pair
//! and applies it once (the fused first product); it writes what the path stores, and
//! every byte written is also read first (the cache's write-allocate: the line is
//! fetched before it is overwritten), so it moves twice [`Path::written`]. All three
//! paths exist in the kernel:
//! [`Path::Stored`] is the default, [`Path::Compact`] is
//! `Params::compact_products`, [`Path::Recompute`] is `Params::matrix_free`; the first
//! and last give the same bits.
//!
//! Two things the model leaves out, both measured on a 16-core Xeon (docs/BENCHMARKS.md,
//! "The pool behind `Threads`"): the rounds' own cost (with rayon 1.5-3 ms a round
//! beyond the busiest thread and 3.8 ms of waiting outside the rounds, a fifth of the
//! matrix-free step; with this crate's [`pool`](crate::pool) a few microseconds a
//! round, a prediction not yet measured there), and the rise of one core's time a pair
//! when every core runs (1.4x for the recompute path there), which bounds the
//! recompute path's speedup at `t / 1.4` where the model says `t`.

/// A way to apply the mobility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// Stream the stored `f64` blocks, symmetric (free space: six entries a block,
    /// `hydrorattle::linalg::Sym`): 48 bytes and 36 flops a pair. (A wall's or a box's
    /// general blocks take 72 bytes.)
    Stored,
    /// Stream the compact `f32` copy: 24 bytes and 36 `f32` flops a pair.
    Compact,
    /// Evaluate every pair where it is used: no bytes, 63 + 36 flops a pair.
    Recompute,
    /// Stream general `f64` blocks (nine entries): 72 bytes and 36 flops a pair. A
    /// wall's and a box's mobility, and the free-space one before it was stored
    /// symmetric (what the 16-core measurement ran). Not among [`Path::ALL`]:
    /// in free space the symmetric blocks do the same work on fewer bytes.
    General,
}

impl Path {
    /// Every path, in the order of [`Machine::ns`].
    pub const ALL: [Path; 3] = [Path::Stored, Path::Compact, Path::Recompute];

    /// Bytes a product reads per pair.
    pub const fn bytes(self) -> f64 {
        match self {
            Path::Stored => 48.0,
            Path::Compact => 24.0,
            Path::Recompute => 0.0,
            Path::General => 72.0,
        }
    }

    /// Bytes the assembly pass writes per pair (the stored blocks, and the copy).
    pub const fn written(self) -> f64 {
        match self {
            Path::Stored => 48.0,
            Path::Compact => 72.0,
            Path::Recompute => 0.0,
            Path::General => 72.0,
        }
    }
}

/// What the model knows of a machine and a step (measured by `examples/bandwidth.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Machine {
    /// One thread's read bandwidth, bytes per ns (GB/s).
    pub b1: f64,
    /// The machine's read bandwidth, bytes per ns (GB/s).
    pub b: f64,
    /// One thread's time per pair of a product on each path ([`Path::ALL`] order, then
    /// [`Path::General`]), ns.
    pub ns: [f64; 4],
    /// One thread's time per pair of the assembly pass that stores the blocks and
    /// applies them once (`parallel::assemble_apply`), ns; the compact path's packing of
    /// its copy, row by row in cache, is taken as free (measured within 2 % of it at
    /// N = 4096, docs/BENCHMARKS.md). The recompute path's pass is a product.
    pub assembly: f64,
    /// The step's serial work per pair (the Krylov vectors, the band Cholesky, the
    /// forces, the copies), ns: the same on any number of threads.
    pub serial: f64,
}

impl Machine {
    /// ns per pair of one product on `path` with `t` threads.
    pub fn product(&self, path: Path, t: f64) -> f64 {
        self.pass(self.ns[path as usize], path.bytes(), t)
    }

    /// ns per pair of a pass doing `ns` of one core's work and moving `bytes` a pair.
    fn pass(&self, ns: f64, bytes: f64, t: f64) -> f64 {
        let bw = (t * self.b1).min(self.b);
        (bytes / bw).max(ns / t)
    }

    /// ns per pair of the assembly pass on `path` with `t` threads: its blocks'
    /// evaluation and first product, and twice the bytes it stores (write-allocate).
    pub fn assembly(&self, path: Path, t: f64) -> f64 {
        let ns = match path {
            Path::Recompute => self.ns[Path::Recompute as usize],
            _ => self.assembly,
        };
        self.pass(ns, 2.0 * path.written(), t)
    }

    /// ns per pair of an Overdamped step on `path` with `t` threads and `k` products
    /// after the assembly pass.
    pub fn step(&self, path: Path, t: f64, k: f64) -> f64 {
        self.assembly(path, t) + k * self.product(path, t) + self.serial
    }

    /// The fastest path for `t` threads and `k` products a step.
    pub fn fastest(&self, t: f64, k: f64) -> Path {
        let time = |p: &Path| self.step(*p, t, k);
        Path::ALL
            .into_iter()
            .min_by(|a, b| time(a).total_cmp(&time(b)))
            .unwrap_or(Path::Stored)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked cases: compute-bound work divides by the threads, bandwidth-bound
    /// work stops at the machine's bandwidth, and the fastest path follows.
    #[test]
    fn the_model_by_hand() {
        let m = Machine {
            b1: 10.0,
            b: 30.0,
            ns: [6.0, 3.0, 15.0, 6.0],
            assembly: 16.0,
            serial: 0.5,
        };
        // Stored, 1 thread: max(48 / 10, 6) = 6; 16 threads: max(48 / 30, 6 / 16) = 1.6.
        assert_eq!(m.product(Path::Stored, 1.0), 6.0);
        assert_eq!(m.product(Path::Stored, 16.0), 1.6);
        // General blocks: max(72 / 10, 6) = 7.2 and max(72 / 30, 6 / 16) = 2.4.
        assert_eq!(m.product(Path::General, 1.0), 7.2);
        assert_eq!(m.product(Path::General, 16.0), 2.4);
        // Recompute: 15 / t, whatever the bandwidth.
        assert_eq!(m.product(Path::Recompute, 16.0), 15.0 / 16.0);
        // The assembly moves twice what it stores: stored 96 bytes, 1 thread
        // max(9.6, 16) = 16; 16 threads max(96 / 30, 1) = 3.2. Compact 144 bytes.
        assert_eq!(m.assembly(Path::Stored, 1.0), 16.0);
        assert_eq!(m.assembly(Path::Stored, 16.0), 3.2);
        assert_eq!(m.assembly(Path::Compact, 1.0), 16.0);
        // A step of 5 products, 1 thread: stored 16 + 5 x 6 + 0.5 = 46.5, compact
        // 16 + 5 x max(2.4, 3) + 0.5 = 31.5, recompute 6 x 15 + 0.5 = 90.5.
        assert_eq!(m.step(Path::Stored, 1.0, 5.0), 46.5);
        assert!((m.step(Path::Compact, 1.0, 5.0) - 31.5).abs() < 1e-12);
        assert_eq!(m.step(Path::Recompute, 1.0, 5.0), 90.5);
        assert_eq!(m.fastest(1.0, 5.0), Path::Compact);
        // 64 threads: stored 3.2 + 5 x 1.6 + 0.5 = 11.7, compact 4.8 + 5 x 0.8 + 0.5
        // = 9.3, recompute 90 / 64 + 0.5 = 1.91: the pair work wins once it is spread
        // thin enough; the serial rest bounds every speedup (recompute 90.5 / 1.91 =
        // 47x, not 64x).
        assert_eq!(m.fastest(64.0, 5.0), Path::Recompute);
        let speedup = m.step(Path::Recompute, 1.0, 5.0) / m.step(Path::Recompute, 64.0, 5.0);
        assert!((speedup - 90.5 / (90.0 / 64.0 + 0.5)).abs() < 1e-12);
    }
}
