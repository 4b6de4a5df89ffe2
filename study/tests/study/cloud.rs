//! The falling cloud's analysis (`hydrorattle_study::cloud`) on synthetic clouds whose
//! answer is known in closed form: a uniform ball (flat density `N / (4/3 pi R^3)`, no
//! hole on the axis), a solid torus (no sphere within `R_t - a_t` of the axis), a ball
//! with a tail of known size above it, a rigid motion plus a known radial flow, and the
//! flatness of a ball, a spheroid and a torus (their second moments in closed form).

use hydrorattle_study::cloud::{
    axis_map, axis_ratio, axis_rings, axis_slice, ball_radius, core, flatness, ring_ratio,
};

/// A small deterministic generator (xorshift64*), uniform in `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn in_cube(&mut self, half: f64) -> [f64; 3] {
        [0, 1, 2].map(|_| half * (2.0 * self.next() - 1.0))
    }
}

/// `n` points uniform in a ball of radius `r` about `c` (by rejection).
fn ball(rng: &mut Rng, n: usize, r: f64, c: [f64; 3]) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = rng.in_cube(r);
        if p.iter().map(|v| v * v).sum::<f64>() < r * r {
            out.push([p[0] + c[0], p[1] + c[1], p[2] + c[2]]);
        }
    }
    out
}

/// `n` points uniform in a solid torus of major radius `big` and tube radius `tube`
/// about the vertical axis through `c`.
fn torus(rng: &mut Rng, n: usize, big: f64, tube: f64, c: [f64; 3]) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(n);
    let half = big + tube;
    while out.len() < n {
        let [x, y, _] = rng.in_cube(half);
        let z = tube * (2.0 * rng.next() - 1.0);
        let d = x.hypot(y) - big;
        if d * d + z * z < tube * tube {
            out.push([x + c[0], y + c[1], z + c[2]]);
        }
    }
    out
}

#[test]
fn a_uniform_ball_has_flat_density_and_no_hole() {
    let (n, r, c) = (200_000, 10.0, [3.0, -2.0, 50.0]);
    let pts = ball(&mut Rng(7), n, r, c);
    let core = core(&pts, &[], r);
    assert_eq!((core.count, core.tail, core.ahead), (n, 0, 0));
    for (got, want) in core.centre.iter().zip(c) {
        assert!((got - want).abs() < 0.05, "centre {:?}", core.centre);
    }
    // Cells well inside the ball (r <= 6, |z| <= 6) hold the ball's density.
    let map = axis_map(&pts, &[], &core, (6.0, 6.0), (3, 3));
    let rho = n as f64 / (4.0 / 3.0 * std::f64::consts::PI * r.powi(3));
    for (k, d) in map.density.iter().enumerate() {
        // Each cell holds at least pi 2^2 4 rho = 2400 points: 4 sigma is below 9 %.
        assert!((d / rho - 1.0).abs() < 0.09, "cell {k}: {d} against {rho}");
    }
    let c = core.centre;
    let inside = pts
        .iter()
        .filter(|p| (p[0] - c[0]).hypot(p[1] - c[1]) < 6.0 && (p[2] - c[2]).abs() < 6.0)
        .count();
    assert_eq!(map.count.iter().sum::<usize>(), inside);
    // sqrt(5/3 <r^2>): <r^2> scatters by sqrt(3/7 - 9/25) R^2 / sqrt(N), 0.1 % here.
    assert!((ball_radius(&pts) / r - 1.0).abs() < 0.003);
    let ratio = axis_ratio(&pts, &core, 2.0, 4.0, 8.0).unwrap();
    assert!(ratio > 0.85, "ball's axis ratio {ratio}");
}

#[test]
fn a_torus_has_a_hole_on_the_axis() {
    let (big, tube, c) = (6.0, 2.5, [0.0, 1.0, -20.0]);
    let pts = torus(&mut Rng(11), 100_000, big, tube, c);
    let core = core(&pts, &[], big + tube);
    assert!((core.centre[2] - c[2]).abs() < 0.05);
    // Nothing lies within big - tube = 3.5 of the axis: the first two rings of width
    // 1.5 are empty at every height, and the densest cell is near r = big, z = 0.
    let map = axis_map(&pts, &[], &core, (9.0, 3.0), (6, 4));
    for iz in 0..4 {
        assert_eq!(map.count[iz * 6], 0);
        assert_eq!(map.count[iz * 6 + 1], 0);
    }
    let densest = (0..24).max_by(|&a, &b| map.density[a].total_cmp(&map.density[b]));
    let (r, z) = map.cell_centre(densest.unwrap() % 6, densest.unwrap() / 6);
    assert!(
        (r - big).abs() <= 1.5 && z.abs() <= 1.5,
        "densest at {r}, {z}"
    );
    assert_eq!(axis_ratio(&pts, &core, 2.0, 2.0, 10.0), Some(0.0));
    // The slice through the axis crosses the tube twice, never the hole.
    let slice = axis_slice(&pts, &core, 0.5);
    assert!(!slice.is_empty());
    assert!(slice.iter().all(|(x, _)| x.abs() > big - tube - 0.1));
}

#[test]
fn a_tail_above_the_ball_is_counted_and_left_out_of_the_core() {
    let (r, c) = (10.0, [0.0, 0.0, 0.0]);
    let mut pts = ball(&mut Rng(3), 9_000, r, c);
    // 1000 spheres on a line from 2 to 12 radii above the centre: all beyond 1.5 R.
    pts.extend((0..1000).map(|k| [0.0, 0.0, r * (2.0 + 10.0 * k as f64 / 1000.0)]));
    let core = core(&pts, &[], r);
    assert_eq!((core.count, core.tail, core.ahead), (9_000, 1_000, 0));
    assert!(
        core.centre.iter().all(|v| v.abs() < 0.2),
        "{:?}",
        core.centre
    );
}

#[test]
fn velocities_are_taken_in_the_cores_frame() {
    let (r, fall) = (10.0, [0.5, 0.0, -120.0]);
    let pts = ball(&mut Rng(5), 50_000, r, [0.0; 3]);
    // The cloud falls at `fall`, and each sphere moves outward at 0.1 of its distance
    // from the axis and upward at 0.2 of its height.
    let c0 = core(&pts, &[], r).centre;
    let vel: Vec<[f64; 3]> = pts
        .iter()
        .map(|p| {
            let (x, y, z) = (p[0] - c0[0], p[1] - c0[1], p[2] - c0[2]);
            [fall[0] + 0.1 * x, fall[1] + 0.1 * y, fall[2] + 0.2 * z]
        })
        .collect();
    let core = core(&pts, &vel, r);
    for (got, want) in core.velocity.iter().zip(fall) {
        assert!((got - want).abs() < 1e-9, "{:?}", core.velocity);
    }
    let map = axis_map(&pts, &vel, &core, (6.0, 6.0), (3, 3));
    for iz in 0..3 {
        for ir in 0..3 {
            let k = iz * 3 + ir;
            let (rc, zc) = map.cell_centre(ir, iz);
            let [ur, uz] = map.velocity[k];
            // The cell's mean of 0.1 r and 0.2 z: within the cell's half width.
            assert!((ur - 0.1 * rc).abs() < 0.1, "u_r {ur} at {rc}");
            assert!(
                (uz - 0.2 * zc).abs() < 0.2 * 0.5 * 4.0 / 2.0,
                "u_z {uz} at {zc}"
            );
        }
    }
}

/// `sqrt(2) z_rms / r_rms` in closed form: 1 for a ball, `C / A` for a spheroid (a ball
/// squashed along `z`), `sqrt(2 (b^2 / 4) / (R_t^2 + 3 b^2 / 4))` for a solid torus
/// (its moments by Pappus: `<z^2> = b^2 / 4`, `<r^2> = R_t^2 + 3 b^2 / 4`).
#[test]
fn flatness_is_one_for_a_ball_and_the_axes_ratio_for_a_spheroid() {
    let r = 10.0;
    let pts = ball(&mut Rng(5), 100_000, r, [0.0, 0.0, 0.0]);
    let c = core(&pts, &[], r);
    let ball_f = flatness(&pts, &c, 1.5 * r).unwrap();
    // Second moments of 10^5 points scatter by about 0.3 %.
    assert!((ball_f - 1.0).abs() < 0.01, "ball {ball_f}");
    let squashed: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], 0.4 * p[2]]).collect();
    let c = core(&squashed, &[], r);
    let f = flatness(&squashed, &c, 1.5 * r).unwrap();
    assert!((f / ball_f - 0.4).abs() < 1e-12, "spheroid {f}");
    let (big, tube) = (6.0, 2.5);
    let pts = torus(&mut Rng(13), 100_000, big, tube, [1.0, 2.0, 3.0]);
    let c = core(&pts, &[], big + tube);
    let want = (2.0 * tube * tube / 4.0 / (big * big + 0.75 * tube * tube)).sqrt();
    let got = flatness(&pts, &c, big + tube).unwrap();
    assert!(
        (got / want - 1.0).abs() < 0.01,
        "torus {got} against {want}"
    );
    assert_eq!(flatness(&[], &c, 1.0), None);
}

/// Ring counts add over frames, and their ratio weighs each ring by its area: each
/// ring of a uniform ball holds its closed-form share, and a torus's pooled frames keep
/// their hole.
#[test]
fn ring_counts_pool_over_frames() {
    assert_eq!(ring_ratio(&[3, 9, 5]), Some(1.0));
    assert_eq!(ring_ratio(&[0, 3, 10]), Some(0.0));
    assert_eq!(ring_ratio(&[0, 0]), None);
    let (n, r, width, slab) = (20_000, 10.0, 2.0, 4.0);
    let a = ball(&mut Rng(21), n, r, [0.0; 3]);
    let b = ball(&mut Rng(22), n, r, [0.0; 3]);
    let (ca, cb) = (core(&a, &[], r), core(&b, &[], r));
    let (ra, rb) = (
        axis_rings(&a, &ca, width, slab, 8.0),
        axis_rings(&b, &cb, width, slab, 8.0),
    );
    // Ring k (inside the ball: sqrt(8^2 + 2^2) < 10) holds rho pi w^2 (2k + 1) slab
    // spheres on average, rho = n / (4/3 pi r^3); 4 Poisson sigmas of the pooled count.
    let rho = n as f64 / (4.0 / 3.0 * std::f64::consts::PI * r.powi(3));
    for (k, (x, y)) in ra.iter().zip(&rb).enumerate() {
        let mean = rho * std::f64::consts::PI * width * width * (2 * k + 1) as f64 * slab;
        let pooled = (x + y) as f64;
        assert!(
            (pooled - 2.0 * mean).abs() < 4.0 * (2.0 * mean).sqrt(),
            "ring {k}: {pooled} against {}",
            2.0 * mean
        );
    }
    let both: Vec<usize> = ra.iter().zip(&rb).map(|(x, y)| x + y).collect();
    // The pooled ball still has no hole.
    assert!(ring_ratio(&both).unwrap() > 0.85);
    // Two frames of a torus (hole of radius 3.5 > 2 rings) pool to an empty axis ring.
    let t1 = torus(&mut Rng(23), 20_000, 6.0, 2.5, [0.0; 3]);
    let t2 = torus(&mut Rng(24), 20_000, 6.0, 2.5, [5.0, 0.0, 0.0]);
    let (c1, c2) = (core(&t1, &[], 8.5), core(&t2, &[], 8.5));
    let pooled: Vec<usize> = axis_rings(&t1, &c1, 1.5, 2.0, 9.0)
        .iter()
        .zip(&axis_rings(&t2, &c2, 1.5, 2.0, 9.0))
        .map(|(x, y)| x + y)
        .collect();
    assert_eq!(ring_ratio(&pooled), Some(0.0));
}
