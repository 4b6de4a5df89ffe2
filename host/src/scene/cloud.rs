//! The cloud generator: the `[cloud]` table, spheres at random in a ball in open fluid.
//!
//! ```toml
//! [cloud]
//! count = 10000          # spheres (>= 1)
//! cloud_radius = 100.0   # R: every sphere lies wholly inside the ball of radius R
//! radius = 1.0           # mean sphere radius (> 0)
//! polydispersity = 0.0   # radii uniform in [radius (1 - p), radius (1 + p)], 0 <= p < 1
//! density = 4.5          # every sphere's density (>= 0)
//! centre = [0, 0, 0]     # the ball's centre
//! seed = 1               # the placement's generator (>= 0)
//! ```
//!
//! The radii are drawn first, then the spheres are placed largest first by random
//! sequential addition: a centre drawn uniformly in the ball of radius `R - a` (so the
//! sphere lies inside the ball of radius `R`; points of the enclosing cube outside it
//! are drawn again) is kept when it clears every sphere already placed by a gap of
//! [`GAP`] of the two radii' sum; else it is drawn again. The centres are then
//! uniform in their ball (radial distribution `r^3 / (R - a)^3`) but for the hard-core
//! exclusion, which at volume fraction `phi` changes the local density by `O(phi)`.
//! The same table gives the same spheres, bit for bit (the kernel's generator,
//! [`hydrorattle::Noise::uniform`]). A grid of cells at least one largest diameter
//! wide keeps each trial `O(1)`. A cloud whose spheres fill more than
//! [`MAX_FRACTION`] of the ball is refused at `cloud_radius` (random sequential
//! addition jams near 0.38), and a placement that needs more than
//! [`TRIALS_PER_SPHERE`] times `count` draws is refused at the table.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S, finite_vector, number};
use super::{DEFAULT_DENSITY, GAP, MAX_FRACTION, Particle, TRIALS_PER_SPHERE};

/// N spheres at random in a ball of radius `R` in open fluid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Cloud {
    /// Number of spheres (>= 1).
    pub count: usize,
    /// The ball's radius `R`: every sphere lies wholly inside it.
    pub cloud_radius: f64,
    /// Mean sphere radius (> 0). Default 1.
    pub radius: f64,
    /// Relative half-width of the uniform radius distribution, `0 <= p < 1`. Default 0.
    pub polydispersity: f64,
    /// Density of every sphere (>= 0). Default [`DEFAULT_DENSITY`].
    pub density: f64,
    /// The ball's centre. Default the origin.
    pub centre: [f64; 3],
    /// Seed of the placement. Default 1.
    pub seed: u64,
}

/// `[cloud]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCloud {
    count: S<usize>,
    cloud_radius: S<f64>,
    radius: S<f64>,
    polydispersity: S<f64>,
    density: S<f64>,
    centre: S<[f64; 3]>,
    seed: S<i64>,
}

impl RawCloud {
    /// Span of `count` (where a storage refusal is placed), when given.
    pub(super) fn count_span(&self) -> Option<std::ops::Range<usize>> {
        self.count.as_ref().map(|c| c.span())
    }
}

/// Resolves `[cloud]` (its span places a missing key); a cloud too dense for random
/// placement is refused at `cloud_radius`.
pub(super) fn resolve(raw: &Spanned<RawCloud>) -> Result<Cloud, Issue> {
    let r = raw.get_ref();
    let missing = |key: &str, what: &str| {
        issue(
            raw.span(),
            format!("missing field `{key}` in [cloud] ({what})"),
        )
    };
    let count = match &r.count {
        None => return Err(missing("count", "the number of spheres")),
        Some(c) if *c.get_ref() == 0 => return Err(issue(c.span(), "cloud count must be >= 1")),
        Some(c) => *c.get_ref(),
    };
    let Some(big) = &r.cloud_radius else {
        return Err(missing("cloud_radius", "the radius of the ball"));
    };
    let cloud_radius = number(&r.cloud_radius, 0.0, "cloud_radius", Bound::Positive)?;
    let radius = number(&r.radius, 1.0, "cloud radius", Bound::Positive)?;
    let p = number(
        &r.polydispersity,
        0.0,
        "cloud polydispersity",
        Bound::NonNegative,
    )?;
    if let Some(s) = r.polydispersity.as_ref().filter(|_| p >= 1.0) {
        return Err(issue(
            s.span(),
            format!("cloud polydispersity must be below 1 (radii stay positive), not {p}"),
        ));
    }
    let density = number(
        &r.density,
        DEFAULT_DENSITY,
        "cloud density",
        Bound::NonNegative,
    )?;
    let centre = match &r.centre {
        None => [0.0; 3],
        Some(c) => finite_vector(c, "cloud centre")?,
    };
    let seed = match &r.seed {
        None => 1,
        Some(s) => {
            u64::try_from(*s.get_ref()).map_err(|_| issue(s.span(), "cloud seed must be >= 0"))?
        }
    };
    let cloud = Cloud {
        count,
        cloud_radius,
        radius,
        polydispersity: p,
        density,
        centre,
        seed,
    };
    let largest = radius * (1.0 + p);
    if largest > cloud_radius {
        return Err(issue(
            big.span(),
            format!(
                "cloud_radius {cloud_radius} is smaller than the largest sphere's radius {largest}: no sphere fits"
            ),
        ));
    }
    // The mean volume of a sphere with radii uniform in a(1 +- p): a^3 (1 + p^2).
    let fraction = count as f64 * radius.powi(3) * (1.0 + p * p) / cloud_radius.powi(3);
    if fraction > MAX_FRACTION {
        let least = cloud_radius * (fraction / MAX_FRACTION).cbrt();
        return Err(issue(
            big.span(),
            format!(
                "{count} spheres fill {fraction:.3} of a ball of radius {cloud_radius}, above {MAX_FRACTION}: \
                 random sequential addition jams near 0.38; give cloud_radius >= {least:.4}"
            ),
        ));
    }
    Ok(cloud)
}

/// Spheres in a ball, at least a gap apart: a grid of cells over the ball's cube,
/// each listing the spheres whose centre it holds.
struct Grid {
    cells: usize,
    width: f64,
    /// The cube's lower corner, relative to the ball's centre.
    low: f64,
    members: Vec<Vec<usize>>,
}

impl Grid {
    /// Cells at least `reach` wide over the cube of half-edge `half`, about one per
    /// sphere at most (`count` spheres).
    fn new(half: f64, reach: f64, count: usize) -> Grid {
        let most = (count as f64).cbrt().ceil() as usize + 1;
        let cells = ((2.0 * half / reach).floor() as usize).clamp(1, most);
        Grid {
            cells,
            width: 2.0 * half / cells as f64,
            low: -half,
            members: vec![Vec::new(); cells * cells * cells],
        }
    }

    fn cell_of(&self, p: [f64; 3]) -> [usize; 3] {
        p.map(|x| (((x - self.low) / self.width).max(0.0) as usize).min(self.cells - 1))
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[0] * self.cells + c[1]) * self.cells + c[2]
    }

    /// The spheres in the cells around `p` (the cells at the cube's faces clamped).
    fn near(&self, p: [f64; 3]) -> impl Iterator<Item = usize> + '_ {
        let c = self.cell_of(p);
        let span = |a: usize| a.saturating_sub(1)..=(a + 1).min(self.cells - 1);
        span(c[0])
            .flat_map(move |x| span(c[1]).flat_map(move |y| span(c[2]).map(move |z| [x, y, z])))
            .flat_map(move |cell| self.members[self.index(cell)].iter().copied())
    }

    fn insert(&mut self, k: usize, p: [f64; 3]) {
        let i = self.index(self.cell_of(p));
        self.members[i].push(k);
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    super::raw::distance(a, b)
}

impl Cloud {
    /// The spheres, or why they cannot be placed.
    pub fn generate(&self) -> Result<Vec<Particle>, String> {
        let mut noise = hydrorattle::Noise::new(self.seed);
        let p = self.polydispersity;
        let radii: Vec<f64> = (0..self.count)
            .map(|_| match p > 0.0 {
                true => self.radius * (1.0 + p * (2.0 * noise.uniform() - 1.0)),
                false => self.radius,
            })
            .collect();
        let a_max = radii.iter().fold(0.0_f64, |m, &a| m.max(a));
        let big = self.cloud_radius;
        // Largest first: the hardest to fit go in while there is room.
        let mut order: Vec<usize> = (0..self.count).collect();
        order.sort_by(|&i, &j| radii[j].total_cmp(&radii[i]).then(i.cmp(&j)));
        let mut grid = Grid::new(big, 2.0 * a_max * (1.0 + GAP), self.count);
        let mut centre = vec![[0.0; 3]; self.count];
        let draws = TRIALS_PER_SPHERE.saturating_mul(self.count);
        let mut budget = draws;
        for (placed, &k) in order.iter().enumerate() {
            let room = big - radii[k];
            loop {
                if budget == 0 {
                    return Err(format!(
                        "placed {placed} of {} spheres in {draws} draws: the cloud is too dense for random sequential addition; give a larger cloud_radius",
                        self.count
                    ));
                }
                budget -= 1;
                let x = point_in_ball(&mut noise, room);
                let clear = grid
                    .near(x)
                    .all(|j| distance(x, centre[j]) >= (radii[k] + radii[j]) * (1.0 + GAP));
                if clear {
                    centre[k] = x;
                    grid.insert(k, x);
                    break;
                }
            }
        }
        let c = self.centre;
        Ok((0..self.count)
            .map(|k| Particle {
                position: std::array::from_fn(|d| c[d] + centre[k][d]),
                radius: radii[k],
                density: self.density,
                ..Particle::default()
            })
            .collect())
    }
}

/// A point uniform in the ball of radius `room` about the origin: points of the cube
/// drawn until one falls inside (about two draws of three deviates).
fn point_in_ball(noise: &mut hydrorattle::Noise, room: f64) -> [f64; 3] {
    loop {
        let x: [f64; 3] = std::array::from_fn(|_| (2.0 * noise.uniform() - 1.0) * room);
        if x.iter().map(|v| v * v).sum::<f64>() <= room * room {
            return x;
        }
    }
}
