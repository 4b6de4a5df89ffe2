//! A falling cloud's shape from a run's frames: its core (centre and velocity), the
//! spheres leaked into its tail, the number density averaged about its vertical axis in
//! `(r, z)` with the mean velocity there in the core's frame, and the torus criterion
//! (the density on the axis in the core's mid-plane against the densest ring there).
//!
//! Gravity is along `-z`, so the cloud falls downwards and its tail trails above it. A
//! torus shows as a hole on the axis of the `(r, z)` map: side and top projections fill
//! that hole with the spheres in front of and behind the axis.

/// How far (in `z`, in units of the initial cloud radius) from the core's centre a
/// sphere still belongs to the core; spheres farther above it are the tail.
pub const CORE_REACH: f64 = 1.5;

/// Fixed-point iterations of [`core`] at most (it settles in a few).
const CORE_ITERATIONS: usize = 100;

/// The cloud's core: the spheres within [`CORE_REACH`] initial radii of its centre in
/// height, the centre being their mean (a fixed point found from the median height).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Core {
    /// Mean position of the core's spheres.
    pub centre: [f64; 3],
    /// Mean velocity of the core's spheres: the cloud's speed.
    pub velocity: [f64; 3],
    /// Spheres in the core.
    pub count: usize,
    /// Spheres above the core (`z > centre + reach`): the tail.
    pub tail: usize,
    /// Spheres below the core (`z < centre - reach`).
    pub ahead: usize,
}

fn mean_of(points: &[[f64; 3]], pick: impl Fn(usize) -> bool) -> ([f64; 3], usize) {
    let mut s = [0.0; 3];
    let mut n = 0;
    for (_, p) in points.iter().enumerate().filter(|(i, _)| pick(*i)) {
        for c in 0..3 {
            s[c] += p[c];
        }
        n += 1;
    }
    let n_f = n.max(1) as f64;
    (s.map(|v| v / n_f), n)
}

/// The core of a cloud of initial radius `radius` (see [`Core`]). `velocities` may be
/// empty (the velocity is then zero). The height starts at the median, which lies in
/// the core while the tail holds fewer than half the spheres.
pub fn core(positions: &[[f64; 3]], velocities: &[[f64; 3]], radius: f64) -> Core {
    let reach = CORE_REACH * radius;
    let mut heights: Vec<f64> = positions.iter().map(|p| p[2]).collect();
    heights.sort_by(f64::total_cmp);
    let mut zc = heights.get(heights.len() / 2).copied().unwrap_or(0.0);
    let inside = |zc: f64, i: usize| (positions[i][2] - zc).abs() <= reach;
    for _ in 0..CORE_ITERATIONS {
        let (m, n) = mean_of(positions, |i| inside(zc, i));
        if n == 0 || m[2] == zc {
            break;
        }
        zc = m[2];
    }
    let (mut centre, count) = mean_of(positions, |i| inside(zc, i));
    centre[2] = zc;
    let velocity = match velocities.len() == positions.len() {
        true => mean_of(velocities, |i| inside(zc, i)).0,
        false => [0.0; 3],
    };
    let tail = positions.iter().filter(|p| p[2] > zc + reach).count();
    let ahead = positions.iter().filter(|p| p[2] < zc - reach).count();
    Core {
        centre,
        velocity,
        count,
        tail,
        ahead,
    }
}

/// The radius of a uniform ball of centres estimated from them: `sqrt(5/3)` times their
/// root-mean-square distance from their mean (a uniform ball's `<r^2>` is `3 R^2 / 5`),
/// which, unlike the largest distance, does not hang on one sphere or on the mean's
/// offset from the ball's centre.
pub fn ball_radius(positions: &[[f64; 3]]) -> f64 {
    let (m, n) = mean_of(positions, |_| true);
    let sum: f64 = positions
        .iter()
        .map(|p| (0..3).map(|j| (p[j] - m[j]).powi(2)).sum::<f64>())
        .sum();
    (5.0 / 3.0 * sum / n.max(1) as f64).sqrt()
}

/// Number density and mean velocity on a grid in `(r, z)` about the core's vertical
/// axis: `r` the distance from the axis, `z` the height above the core's centre.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisMap {
    /// Largest `r` of the grid (cells are `r_max / nr` wide, from the axis).
    pub r_max: f64,
    /// The grid spans `z` from `-z_half` to `z_half`.
    pub z_half: f64,
    /// Cells in `r`.
    pub nr: usize,
    /// Cells in `z`.
    pub nz: usize,
    /// Spheres in each cell, row by row from the lowest: `count[iz * nr + ir]`.
    pub count: Vec<usize>,
    /// Spheres per unit volume in each cell (the count over the ring's volume).
    pub density: Vec<f64>,
    /// Mean velocity `(u_r, u_z)` of each cell's spheres in the core's frame (zero in
    /// an empty cell).
    pub velocity: Vec<[f64; 2]>,
}

impl AxisMap {
    /// The centre `(r, z)` of cell `(ir, iz)`.
    pub fn cell_centre(&self, ir: usize, iz: usize) -> (f64, f64) {
        let (dr, dz) = (
            self.r_max / self.nr as f64,
            2.0 * self.z_half / self.nz as f64,
        );
        (
            (ir as f64 + 0.5) * dr,
            -self.z_half + (iz as f64 + 0.5) * dz,
        )
    }

    /// The largest density of any cell.
    pub fn peak(&self) -> f64 {
        self.density.iter().copied().fold(0.0, f64::max)
    }
}

/// The [`AxisMap`] of spheres at `positions` (velocities `velocities`, or none) about
/// `core`, on `nr` by `nz` cells over `r < r_max`, `|z| < z_half`.
pub fn axis_map(
    positions: &[[f64; 3]],
    velocities: &[[f64; 3]],
    core: &Core,
    (r_max, z_half): (f64, f64),
    (nr, nz): (usize, usize),
) -> AxisMap {
    let mut count = vec![0usize; nr * nz];
    let mut sum = vec![[0.0f64; 2]; nr * nz];
    let (dr, dz) = (r_max / nr as f64, 2.0 * z_half / nz as f64);
    let c = core.centre;
    for (i, p) in positions.iter().enumerate() {
        let (x, y, z) = (p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        let r = x.hypot(y);
        let (fr, fz) = (r / dr, (z + z_half) / dz);
        if !(fr < nr as f64 && (0.0..nz as f64).contains(&fz)) {
            continue;
        }
        let k = fz as usize * nr + fr as usize;
        count[k] += 1;
        if let Some(v) = velocities.get(i) {
            let u = [0, 1, 2].map(|j| v[j] - core.velocity[j]);
            // On the axis the radial direction is undefined: count no radial speed.
            let ur = match r > 0.0 {
                true => (u[0] * x + u[1] * y) / r,
                false => 0.0,
            };
            sum[k][0] += ur;
            sum[k][1] += u[2];
        }
    }
    let density = (0..nr * nz)
        .map(|k| {
            let ir = (k % nr) as f64;
            let ring = std::f64::consts::PI * dr * dr * ((ir + 1.0).powi(2) - ir.powi(2)) * dz;
            count[k] as f64 / ring
        })
        .collect();
    let velocity = count
        .iter()
        .zip(&sum)
        .map(|(&n, s)| match n {
            0 => [0.0; 2],
            n => s.map(|v| v / n as f64),
        })
        .collect();
    AxisMap {
        r_max,
        z_half,
        nr,
        nz,
        count,
        density,
        velocity,
    }
}

/// The torus criterion: in the slab `|z| < thickness / 2` about the core's centre, the
/// number density within `width` of the axis over the largest density of the rings of
/// width `width` about it, out to `r_max`. About 1 for a ball (less by the counting
/// noise of the densest ring), 0 for a torus whose hole is wider than `width`; `None`
/// when the slab is empty.
pub fn axis_ratio(
    positions: &[[f64; 3]],
    core: &Core,
    width: f64,
    thickness: f64,
    r_max: f64,
) -> Option<f64> {
    ring_ratio(&axis_rings(positions, core, width, thickness, r_max))
}

/// The spheres in each ring of [`axis_ratio`]'s slab (the first about the axis):
/// rings from several frames add up, and [`ring_ratio`] of their sum is the criterion
/// with the counting noise of one frame divided by their number.
pub fn axis_rings(
    positions: &[[f64; 3]],
    core: &Core,
    width: f64,
    thickness: f64,
    r_max: f64,
) -> Vec<usize> {
    let nr = (r_max / width).ceil().max(1.0) as usize;
    let map = axis_map(
        positions,
        &[],
        core,
        (nr as f64 * width, 0.5 * thickness),
        (nr, 1),
    );
    map.count
}

/// [`axis_ratio`] from ring counts ([`axis_rings`], maybe summed over frames): ring
/// `k`'s area grows as `2 k + 1`; `None` when every ring is empty.
pub fn ring_ratio(rings: &[usize]) -> Option<f64> {
    let density = |k: usize| rings[k] as f64 / (2 * k + 1) as f64;
    let peak = (0..rings.len()).map(density).fold(0.0, f64::max);
    (peak > 0.0).then(|| density(0) / peak)
}

/// How flat the core is: `sqrt(2) z_rms / r_rms` over its spheres, `z` measured from
/// its centre's height and `r` from its vertical axis. 1 for a uniform ball and `C / A`
/// for a uniform spheroid of vertical semi-axis `C` and horizontal `A`; a thin torus of
/// tube radius `b` and major radius `R_t` about `b / (sqrt(2) R_t)`. `None` for an
/// empty core.
pub fn flatness(positions: &[[f64; 3]], core: &Core, reach: f64) -> Option<f64> {
    let c = core.centre;
    let (mut zz, mut rr, mut n) = (0.0, 0.0, 0usize);
    for p in positions.iter().filter(|p| (p[2] - c[2]).abs() <= reach) {
        zz += (p[2] - c[2]).powi(2);
        rr += (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
        n += 1;
    }
    (n > 0 && rr > 0.0).then(|| (2.0 * zz / rr).sqrt())
}

/// The positions within `half_width` of the vertical plane through the core's centre
/// (`|y - y_c| < half_width`), as `(x, z)` relative to the centre: a thin slice through
/// the cloud's axis.
pub fn axis_slice(positions: &[[f64; 3]], core: &Core, half_width: f64) -> Vec<(f64, f64)> {
    let c = core.centre;
    positions
        .iter()
        .filter(|p| (p[1] - c[1]).abs() < half_width)
        .map(|p| (p[0] - c[0], p[2] - c[2]))
        .collect()
}
