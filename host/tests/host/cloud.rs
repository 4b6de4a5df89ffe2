//! The `[cloud]` generator: its count, no overlaps, every sphere inside the ball, the
//! same bits from the same seed, centres uniform in their ball (the radial
//! distribution `r^3 / R_c^3`, by the Kolmogorov-Smirnov distance), and its refusals
//! placed at their line.

use hydrorattle_host::scene::{Cloud, Scene};

fn scene(cloud: &str) -> String {
    format!("[cloud]\n{cloud}\n[integrator]\nmethod = \"overdamped\"\ndt = 0.1\nduration = 0.1\n")
}

fn cloud(count: usize, cloud_radius: f64, polydispersity: f64, seed: u64) -> Cloud {
    Cloud {
        count,
        cloud_radius,
        radius: 1.0,
        polydispersity,
        density: 4.5,
        centre: [3.0, -2.0, 7.0],
        seed,
    }
}

fn norm(x: [f64; 3], c: [f64; 3]) -> f64 {
    (0..3).map(|d| (x[d] - c[d]).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn a_cloud_has_its_count_inside_its_ball_without_overlap() {
    // Dense for a cloud (fraction 0.2 of the ball), polydisperse.
    let c = cloud(2000, 2000f64.cbrt() * 1.04 / 0.2f64.cbrt(), 0.3, 5);
    let ps = c.generate().unwrap();
    assert_eq!(ps.len(), c.count);
    for p in &ps {
        assert!(norm(p.position, c.centre) + p.radius <= c.cloud_radius);
        assert!((0.7..=1.3).contains(&p.radius), "{}", p.radius);
    }
    // Every pair, directly (no cell list shared with the generator).
    for i in 0..ps.len() {
        for j in 0..i {
            let s = norm(ps[i].position, ps[j].position);
            assert!(s >= ps[i].radius + ps[j].radius, "{i} {j} overlap");
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_bits_and_another_seed_another_cloud() {
    let bits = |seed| {
        let ps = cloud(500, 20.0, 0.2, seed).generate().unwrap();
        ps.iter()
            .flat_map(|p| p.position.into_iter().chain([p.radius]))
            .map(f64::to_bits)
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(9), bits(9));
    assert_ne!(bits(9), bits(10));
}

#[test]
fn centres_are_uniform_in_their_ball() {
    // Dilute (fraction 0.01): the hard core changes the density by O(1e-2) near the
    // surface, far below the sampling noise tested here.
    let n = 10_000;
    let c = cloud(n, (n as f64 / 0.01).cbrt(), 0.0, 3);
    let room = c.cloud_radius - c.radius;
    let ps = c.generate().unwrap();
    // The centres' radial CDF is (r / room)^3, and each direction's mean is zero.
    let mut u: Vec<f64> = ps
        .iter()
        .map(|p| (norm(p.position, c.centre) / room).powi(3))
        .collect();
    u.sort_by(f64::total_cmp);
    let d = u
        .iter()
        .enumerate()
        .map(|(k, &x)| (x - k as f64 / n as f64).max((k + 1) as f64 / n as f64 - x))
        .fold(0.0, f64::max);
    // Kolmogorov: P(sqrt(n) D > 1.63) = 1 %.
    assert!((n as f64).sqrt() * d < 1.63, "KS distance {d} at n = {n}");
    for axis in 0..3 {
        let mean = ps
            .iter()
            .map(|p| p.position[axis] - c.centre[axis])
            .sum::<f64>()
            / n as f64;
        // Var(x) = room^2 / 5 for a uniform ball: 4 standard errors.
        let se = room / (5.0 * n as f64).sqrt();
        assert!(mean.abs() < 4.0 * se, "axis {axis}: mean {mean}, se {se}");
    }
}

#[test]
fn a_cloud_scene_reads_writes_back_and_repeats() {
    let text = scene("count = 300\ncloud_radius = 15.0\npolydispersity = 0.1\nseed = 4");
    let s = Scene::parse(&text, "cloud.toml").unwrap();
    assert_eq!(s.particles.len(), 300);
    assert!(s.cloud.is_some() && s.periodic.is_none());
    assert!(s.species().iter().all(|&k| k == "sphere"));
    let again = Scene::parse(&s.to_toml(), "written.toml").unwrap();
    assert_eq!(again, s);
}

#[test]
fn refusals_are_placed_at_their_line() {
    let line = |cloud: &str| {
        let e = Scene::parse(&scene(cloud), "c.toml").unwrap_err();
        (e.line(), e.message)
    };
    let (at, m) = line("count = 1000\ncloud_radius = 10.0");
    assert_eq!(at, Some(3), "{m}");
    assert!(
        m.contains("jams") && m.contains("cloud_radius >= 14.1"),
        "{m}"
    );
    let (at, m) = line("count = 10\ncloud_radius = 1.5\nradius = 2.0");
    assert_eq!(at, Some(3), "{m}");
    assert!(m.contains("no sphere fits"), "{m}");
    let (at, m) = line("count = 0\ncloud_radius = 10.0");
    assert_eq!(at, Some(2), "{m}");
    let (at, m) = line("count = 10");
    assert_eq!(at, Some(1), "{m}");
    assert!(m.contains("cloud_radius"), "{m}");
    let (at, m) = line("count = 10\ncloud_radius = 10.0\npolydispersity = 1.0");
    assert_eq!(at, Some(4), "{m}");
    let e = Scene::parse(
        &format!(
            "{}[helix]\ntails = 3\n",
            scene("count = 10\ncloud_radius = 10.0")
        ),
        "c.toml",
    )
    .unwrap_err();
    assert!(e.message.contains("makes its own spheres"), "{}", e.message);
}

#[test]
fn a_placement_that_jams_is_refused_naming_the_draws() {
    // Under the fraction bound (0.35) but near jamming for equal spheres in a ball
    // (whose surface leaves room unused).
    let e = cloud(3000, (3000f64 / 0.345).cbrt(), 0.0, 1)
        .generate()
        .unwrap_err();
    assert!(
        e.contains("too dense for random sequential addition"),
        "{e}"
    );
}
