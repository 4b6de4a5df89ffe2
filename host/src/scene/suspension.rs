//! The periodic suspension generator: the `[suspension]` table.
//!
//! ```toml
//! [suspension]
//! count = 64             # spheres (>= 1)
//! fraction = 0.1         # volume fraction phi, 0 < phi <= MAX_FRACTION
//! radius = 1.0           # mean radius (> 0)
//! polydispersity = 0.2   # radii uniform in [radius (1 - p), radius (1 + p)], 0 <= p < 1
//! density = 4.5          # every sphere's density (>= 0)
//! seed = 1               # the placement's generator (>= 0)
//! ```
//!
//! The box is cubic, its edge `L = (sum 4/3 pi a_i^3 / phi)^(1/3)`, so the spheres
//! fill exactly the fraction asked for; it is the scene's `[box]` (whose `size` is
//! then left out). The radii are drawn first, then the spheres are placed largest
//! first by random sequential addition: a centre drawn uniformly in `[0, L)^3` is kept
//! when it clears every sphere already placed, through the minimum image, by a gap of
//! [`GAP`] of the two radii' sum; else it is drawn again. The same table gives the same
//! spheres, bit for bit (the kernel's generator, [`hydrorattle::Noise::uniform`]).
//! A neighbour grid of cells at least one largest diameter wide (and about one per
//! sphere at most) keeps each trial `O(1)`. Random sequential addition of equal spheres jams near phi = 0.38, so a
//! placement that needs more than [`TRIALS_PER_SPHERE`] times `count` draws is refused
//! (lower the fraction).

use hydrorattle::Periodic;
use hydrorattle::glam::DVec3;
use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S, number};
use super::{DEFAULT_DENSITY, Particle};

/// Largest volume fraction the generator accepts: random sequential addition of equal
/// spheres jams at about 0.38, and its last spheres take ever more draws (2000 equal
/// spheres: 0.33 placed within 500 draws each, 0.35 not); denser suspensions need
/// compression, which this generator does not do.
pub const MAX_FRACTION: f64 = 0.35;
/// Draws allowed per sphere, on average, before the placement is refused.
pub const TRIALS_PER_SPHERE: usize = 2000;
/// The smallest gap left between two spheres, relative to the sum of their radii: they
/// start apart in either precision (f32 rounds a unit-sized position by `6e-8`).
pub const GAP: f64 = 1e-6;

/// N spheres at a volume fraction in a cubic periodic box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Suspension {
    /// Number of spheres (>= 1).
    pub count: usize,
    /// Volume fraction (`0 < fraction <= MAX_FRACTION`).
    pub fraction: f64,
    /// Mean radius (> 0). Default 1.
    pub radius: f64,
    /// Relative half-width of the uniform radius distribution, `0 <= p < 1`. Default 0.
    pub polydispersity: f64,
    /// Density of every sphere (>= 0). Default [`DEFAULT_DENSITY`].
    pub density: f64,
    /// Seed of the placement. Default 1.
    pub seed: u64,
}

/// `[suspension]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSuspension {
    count: S<usize>,
    fraction: S<f64>,
    radius: S<f64>,
    polydispersity: S<f64>,
    density: S<f64>,
    seed: S<i64>,
}

impl RawSuspension {
    /// Span of `count` (where a storage refusal is placed), when given.
    pub(super) fn count_span(&self) -> Option<std::ops::Range<usize>> {
        self.count.as_ref().map(|c| c.span())
    }
}

/// Resolves `[suspension]` (its span places a missing key).
pub(super) fn resolve(raw: &Spanned<RawSuspension>) -> Result<Suspension, Issue> {
    let r = raw.get_ref();
    let missing = |key: &str, what: &str| {
        issue(
            raw.span(),
            format!("missing field `{key}` in [suspension] ({what})"),
        )
    };
    let count = match &r.count {
        None => return Err(missing("count", "the number of spheres")),
        Some(c) if *c.get_ref() == 0 => {
            return Err(issue(c.span(), "suspension count must be >= 1"));
        }
        Some(c) => *c.get_ref(),
    };
    if r.fraction.is_none() {
        return Err(missing("fraction", "the volume fraction"));
    }
    let fraction = number(&r.fraction, 0.0, "suspension fraction", Bound::Positive)?;
    if let Some(f) = r.fraction.as_ref().filter(|_| fraction > MAX_FRACTION) {
        return Err(issue(
            f.span(),
            format!(
                "suspension fraction {fraction} is above {MAX_FRACTION}: random sequential addition jams near 0.38"
            ),
        ));
    }
    let radius = number(&r.radius, 1.0, "suspension radius", Bound::Positive)?;
    let p = number(
        &r.polydispersity,
        0.0,
        "suspension polydispersity",
        Bound::NonNegative,
    )?;
    if let Some(s) = r.polydispersity.as_ref().filter(|_| p >= 1.0) {
        return Err(issue(
            s.span(),
            format!("suspension polydispersity must be below 1 (radii stay positive), not {p}"),
        ));
    }
    let density = number(
        &r.density,
        DEFAULT_DENSITY,
        "suspension density",
        Bound::NonNegative,
    )?;
    let seed = match &r.seed {
        None => 1,
        Some(s) => u64::try_from(*s.get_ref())
            .map_err(|_| issue(s.span(), "suspension seed must be >= 0"))?,
    };
    Ok(Suspension {
        count,
        fraction,
        radius,
        polydispersity: p,
        density,
        seed,
    })
}

/// Spheres at least a gap apart through the minimum image in a cubic box: a grid of
/// cells, each listing the spheres whose centre it holds.
struct Grid {
    cell: hydrorattle::Periodic<f64>,
    cells: usize,
    width: f64,
    members: Vec<Vec<usize>>,
}

impl Grid {
    /// Cells at least `reach` wide, about one per sphere at most (`count` spheres).
    fn new(cell: Periodic<f64>, reach: f64, count: usize) -> Grid {
        let edge = cell.size()[0];
        let most = (count as f64).cbrt().ceil() as usize + 1;
        // At least three cells a side, so the 27 neighbours are distinct cells.
        let cells = ((edge / reach).floor() as usize).clamp(1, most);
        let cells = if cells < 3 { 1 } else { cells };
        Grid {
            cell,
            cells,
            width: edge / cells as f64,
            members: vec![Vec::new(); cells * cells * cells],
        }
    }

    fn cell_of(&self, p: [f64; 3]) -> [usize; 3] {
        p.map(|x| ((x / self.width) as usize).min(self.cells - 1))
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.cells + c[1]) * self.cells + c[2]
    }

    /// The spheres in the cells around `p` (every sphere when the grid has one cell).
    fn near(&self, p: [f64; 3]) -> impl Iterator<Item = usize> + '_ {
        let c = self.cell_of(p);
        let n = self.cells as isize;
        let reach: isize = if self.cells == 1 { 0 } else { 1 };
        let wrap = move |a: usize, d: isize| (a as isize + d).rem_euclid(n) as usize;
        let mut cells = Vec::with_capacity(27);
        for dx in -reach..=reach {
            for dy in -reach..=reach {
                for dz in -reach..=reach {
                    cells.push(self.index([wrap(c[0], dx), wrap(c[1], dy), wrap(c[2], dz)]));
                }
            }
        }
        cells
            .into_iter()
            .flat_map(move |i| self.members[i].iter().copied())
    }

    fn insert(&mut self, k: usize, p: [f64; 3]) {
        let i = self.index(self.cell_of(p));
        self.members[i].push(k);
    }

    /// Centre distance through the minimum image (the kernel's, as the steps take it).
    fn distance(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let d = DVec3::from(a) - DVec3::from(b);
        self.cell.minimum_image(d).length()
    }
}

impl Suspension {
    /// The radii, drawn in order from the generator (all equal without
    /// polydispersity), and the cubic box edge that holds them at the fraction.
    fn radii(&self, noise: &mut hydrorattle::Noise) -> (Vec<f64>, f64) {
        let p = self.polydispersity;
        let radii: Vec<f64> = (0..self.count)
            .map(|_| match p > 0.0 {
                true => self.radius * (1.0 + p * (2.0 * noise.uniform() - 1.0)),
                false => self.radius,
            })
            .collect();
        let volume: f64 = radii
            .iter()
            .map(|&a| 4.0 / 3.0 * std::f64::consts::PI * a * a * a)
            .sum();
        (radii, (volume / self.fraction).cbrt())
    }

    /// The spheres and the cubic box's edge, or why they cannot be placed.
    pub fn generate(&self) -> Result<(Vec<Particle>, f64), String> {
        let mut noise = hydrorattle::Noise::new(self.seed);
        let (radii, edge) = self.radii(&mut noise);
        let a_max = radii.iter().fold(0.0_f64, |m, &a| m.max(a));
        let cell = Periodic::new([edge; 3])
            .map_err(|_| format!("the box edge {edge} is not a finite positive number"))?;
        if 2.0 * a_max >= edge {
            return Err(format!(
                "a sphere of radius {a_max} does not fit in the box of edge {edge} that {} spheres at fraction {} make: give more spheres",
                self.count, self.fraction
            ));
        }
        // Largest first: the hardest to fit go in while there is room.
        let mut order: Vec<usize> = (0..self.count).collect();
        order.sort_by(|&i, &j| radii[j].total_cmp(&radii[i]).then(i.cmp(&j)));
        let mut grid = Grid::new(cell, 2.0 * a_max * (1.0 + GAP), self.count);
        let mut centre = vec![[0.0; 3]; self.count];
        let mut budget = TRIALS_PER_SPHERE.saturating_mul(self.count);
        for (placed, &k) in order.iter().enumerate() {
            loop {
                if budget == 0 {
                    return Err(format!(
                        "placed {placed} of {} spheres in {} draws: fraction {} is too close to jamming for random sequential addition; lower it",
                        self.count,
                        TRIALS_PER_SPHERE.saturating_mul(self.count),
                        self.fraction
                    ));
                }
                budget -= 1;
                let p: [f64; 3] = std::array::from_fn(|_| noise.uniform() * edge);
                let clear = grid
                    .near(p)
                    .all(|j| grid.distance(p, centre[j]) >= (radii[k] + radii[j]) * (1.0 + GAP));
                if clear {
                    centre[k] = p;
                    grid.insert(k, p);
                    break;
                }
            }
        }
        let particles = (0..self.count)
            .map(|k| Particle {
                position: centre[k],
                radius: radii[k],
                density: self.density,
                ..Particle::default()
            })
            .collect();
        Ok((particles, edge))
    }
}
