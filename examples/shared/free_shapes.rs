//! The shapes the free-space cost examples time (shared by `#[path]`, with
//! `shared/splitmix.rs` as the including crate's `splitmix` module): unit spheres in a
//! ball, the helical chain of `benches/kernel/shared.rs`, their bounding box and near
//! pairs.

use hydrorattle::Real;

use crate::splitmix::Rng;

type V = <f64 as Real>::V3;

/// The shapes timed, by name: clouds at three volume fractions and the chain (`None`).
pub const SHAPES: [(&str, Option<f64>); 4] = [
    ("cloud 0.01", Some(0.01)),
    ("cloud 0.1", Some(0.1)),
    ("cloud 0.3", Some(0.3)),
    ("chain", None),
];

/// The sphere counts timed (each example stops at its own largest).
pub const COUNTS: [usize; 10] = [
    10, 30, 100, 300, 1000, 3000, 10_000, 20_000, 50_000, 100_000,
];

/// What a cost example's arguments select: the counts `MAX_N` or `MIN_N:MAX_N` (the
/// first argument, 1e4 without one; a count may be written `1e5`) and the shapes named
/// after it (every shape when none), with both as the recorded command writes them.
pub struct Selection {
    min_n: usize,
    max_n: usize,
    only: Vec<String>,
    /// The counts' argument as given (`"10000"` without one).
    pub range: String,
    /// The shapes' arguments, each quoted after a space.
    pub named: String,
}

impl Selection {
    /// The selection `args` (the example's arguments, its own options removed) make.
    pub fn new(args: &[String]) -> Self {
        let num = |s: &str| s.parse::<f64>().unwrap() as usize;
        let range = args.first().map_or("10000", String::as_str);
        let (min_n, max_n) = match range.split_once(':') {
            Some((a, b)) => (num(a), num(b)),
            None => (0, num(range)),
        };
        let only = args.iter().skip(1).cloned().collect::<Vec<_>>();
        let named = only.iter().map(|s| format!(" '{s}'")).collect();
        Self {
            min_n,
            max_n,
            only,
            range: range.to_string(),
            named,
        }
    }

    /// Whether the shape called `name` runs.
    pub fn shape(&self, name: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|o| o == name)
    }

    /// The counts of [`COUNTS`] that run.
    pub fn counts(&self) -> impl Iterator<Item = usize> + '_ {
        COUNTS
            .into_iter()
            .filter(|n| (self.min_n..=self.max_n).contains(n))
    }
}

/// `n` unit spheres uniformly in a ball at volume fraction `phi`.
pub fn cloud(n: usize, phi: f64, seed: u64) -> Vec<V> {
    let radius = (n as f64 / phi).cbrt();
    let mut rng = Rng(seed);
    let mut pos = Vec::with_capacity(n);
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| radius * (2.0 * rng.unit() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= radius * radius {
            pos.push(f64::v3_from(p));
        }
    }
    pos
}

/// The chain of `benches/kernel/shared.rs`: turning 0.6 rad per bead, rising 0.8, bonds 3
/// (unit beads touching at 1.5 times contact).
pub fn chain(n: usize) -> Vec<V> {
    let mut at = [0.0f64; 3];
    (0..n)
        .map(|k| {
            let t = 0.6 * k as f64;
            let d = [t.cos(), t.sin(), 0.8];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if k > 0 {
                (0..3).for_each(|c| at[c] += 3.0 * d[c] / l);
            }
            f64::v3_from(at)
        })
        .collect()
}

/// The bounding box's edges of `pos`.
pub fn extent(pos: &[V]) -> [f64; 3] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pos {
        let a = f64::v3_to_f64(*p);
        for c in 0..3 {
            lo[c] = lo[c].min(a[c]);
            hi[c] = hi[c].max(a[c]);
        }
    }
    [0, 1, 2].map(|c| hi[c] - lo[c])
}

/// Pairs closer than `cut`, counted in cells of edge `cut` (the fast product's near
/// work).
pub fn near_pairs(pos: &[V], cut: f64) -> usize {
    use std::collections::HashMap;
    let key = |p: &V| f64::v3_to_f64(*p).map(|x| (x / cut).floor() as i64);
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in pos.iter().enumerate() {
        cells.entry(key(p)).or_default().push(i);
    }
    let mut count = 0;
    for (i, p) in pos.iter().enumerate() {
        let k = key(p);
        for d in 0..27i64 {
            let c = [k[0] + d % 3 - 1, k[1] + d / 3 % 3 - 1, k[2] + d / 9 - 1];
            for &j in cells.get(&c).map_or(&[][..], Vec::as_slice) {
                count += usize::from(j > i && f64::norm2(pos[j] - *p) < cut * cut);
            }
        }
    }
    count
}
