//! Shared helpers for the physics validation tests (scenes, snapshots, digests, fits).
//!
//! Each test crate uses a different subset of these helpers.
#![allow(dead_code)]

pub mod boxes;
pub mod fuzz;
pub mod thermal;

use hydrorattle::{
    BondSet, ExternalForce, Method, Params, Particle, ParticleSet, Real, SolverKind, StepError,
    StepReport, Workspace, step,
};

/// Equal-density spheres: density 4.5 with eta = 1 and |g| = 1 gives a lone unit
/// sphere the Stokes speed `U0 = 2/9 rho a^2 g / eta = 1` and momentum relaxation time
/// `tau = m / (6 pi eta a) = 1`.
/// Every integrator, in the order of `Method`'s declaration.
pub const METHODS: [Method; 5] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
    Method::Springs,
];

pub const RHO: f64 = 4.5;

/// `[x, y, z]` in the precision `T`.
pub fn v3<T: Real>(x: f64, y: f64, z: f64) -> T::V3 {
    T::v3_from([x, y, z])
}

/// A vector as `f64` components.
pub fn f64s<T: Real>(v: T::V3) -> [f64; 3] {
    T::v3_to_f64(v)
}

pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Whether spheres of radii `a`, `b` at centre distance `s` may be placed together: with
/// `overlap`, not nested (a tenth of the smaller radius to spare), otherwise apart.
pub fn admissible(s: f64, a: f64, b: f64, overlap: bool) -> bool {
    if overlap {
        s > (a - b).abs() + 0.1 * a.min(b)
    } else {
        s > (a + b) * (1.0 + 1e-9)
    }
}

/// Rodrigues' rotation of `r` about the unit `axis` by `angle`.
pub fn rotate(r: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    let k_x_r = cross(axis, r);
    let k_dot_r = dot(axis, r);
    add(
        add(scale(r, c), scale(k_x_r, s)),
        scale(axis, k_dot_r * (1.0 - c)),
    )
}

/// One step of the front door with the generator `noise` lent to the set for it (it
/// is the set's again afterwards: advanced when the step succeeds, as it was when not).
pub fn step_thermal<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    noise: &mut hydrorattle::Noise,
) -> Result<StepReport<T>, StepError> {
    ps.noise = Some(noise.clone());
    let r = step(ps, bonds, p, ws, ext);
    if let Some(g) = ps.noise.take() {
        *noise = g;
    }
    r
}

/// One sphere as plain data: centre, radius, density.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub pos: [f64; 3],
    pub radius: f64,
    pub density: f64,
}

/// Builds a validated particle set (no overlap allowed).
pub fn particles<T: Real, const N: usize>(spheres: &[Sphere]) -> ParticleSet<T, N> {
    let list: Vec<Particle<T>> = spheres
        .iter()
        .map(|s| {
            Particle::new(
                T::v3_from(s.pos),
                T::from_f64(s.radius),
                T::from_f64(s.density),
            )
        })
        .collect();
    ParticleSet::from_slice(&list, false).expect("valid scene")
}

/// Bond lengths `D (a_i + a_j)` along a path of unit directions: sphere `k + 1` sits at
/// `r_k + D (a_k + a_k+1) dir_k`.
pub fn path(radii: &[f64], dirs: &[[f64; 3]], spacing: f64, density: f64) -> Vec<Sphere> {
    let mut out = vec![Sphere {
        pos: [0.0; 3],
        radius: radii[0],
        density,
    }];
    for k in 1..radii.len() {
        let d = spacing * (radii[k - 1] + radii[k]);
        let u = dirs[k - 1];
        let u = scale(u, 1.0 / norm(u));
        out.push(Sphere {
            pos: add(out[k - 1].pos, scale(u, d)),
            radius: radii[k],
            density,
        });
    }
    out
}

/// The paper's helix (Figure 1a style): head of radius `head` at index 0, `n - 1` tails
/// of radius 1, beads on a helix of radius `helix_radius` about the z axis with rise
/// `rise` per bead, consecutive centres exactly `D (a_i + a_j)` apart.
pub fn helix(n: usize, head: f64, helix_radius: f64, rise: f64, d_hat: f64) -> Vec<Sphere> {
    let mut phi = 0.0f64;
    let mut out: Vec<Sphere> = Vec::with_capacity(n);
    for k in 0..n {
        let radius = if k == 0 { head } else { 1.0 };
        if k > 0 {
            // Chord between consecutive beads: (2 R sin(dphi/2))^2 + rise^2 = d^2.
            let d = d_hat * (out[k - 1].radius + radius);
            let planar = (d * d - rise * rise).sqrt();
            phi += 2.0 * (planar / (2.0 * helix_radius)).asin();
        }
        out.push(Sphere {
            pos: [
                helix_radius * phi.cos(),
                helix_radius * phi.sin(),
                rise * k as f64,
            ],
            radius,
            density: RHO,
        });
    }
    out
}

/// Bit pattern of every state field (positions, velocities, angular velocities, time).
pub fn snapshot<T: Real, const N: usize>(ps: &ParticleSet<T, N>) -> Vec<u64> {
    let n = ps.len();
    let mut out = vec![n as u64, ps.time.to_f64().to_bits()];
    for field in [&ps.pos[..n], &ps.vel[..n], &ps.omega[..n]] {
        for &v in field {
            out.extend(f64s::<T>(v).iter().map(|x| x.to_bits()));
        }
    }
    out
}

/// The bonds of a chain `0-1-...-(n-1)` at its current lengths, of any length (the
/// runtime-sized counterpart of `BondSet::chain`).
pub fn chain_bonds(pos: &[hydrorattle::glam::DVec3]) -> Vec<hydrorattle::Bond<f64>> {
    (1..pos.len())
        .map(|i| hydrorattle::Bond {
            i: i - 1,
            j: i,
            length: (pos[i] - pos[i - 1]).length(),
        })
        .collect()
}

/// FNV-1a (64 bit) over the little-endian bytes of a sequence of words.
pub fn fnv1a(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// Digest of all position and velocity bits. `to_bits()` of the native precision: `f32`
/// values are widened to `f64` first, which is exact and injective on finite values.
pub fn state_digest<T: Real, const N: usize>(ps: &ParticleSet<T, N>) -> u64 {
    let n = ps.len();
    let words = ps.pos[..n]
        .iter()
        .chain(&ps.vel[..n])
        .flat_map(|&v| f64s::<T>(v))
        .map(f64::to_bits);
    fnv1a(words)
}

/// Runs `steps` steps, panicking with context on error; returns every report.
pub fn run<T: Real, const N: usize, const B: usize, E: ExternalForce<T>>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    ext: &mut E,
    steps: usize,
) -> Vec<StepReport<T>> {
    (0..steps)
        .map(|k| {
            step(ps, bonds, p, ws, ext)
                .unwrap_or_else(|e| panic!("{:?} step {k} failed: {e} ({e:?})", p.method))
        })
        .collect()
}

/// Every integrator, in declaration order.
pub const ALL_METHODS: [Method; 5] = [
    Method::Overdamped,
    Method::Overdamped2,
    Method::Rattle,
    Method::RattleStable,
    Method::Springs,
];

/// Parameters with the method and solver kind set.
pub fn params<T: Real>(dt: f64, method: Method, kind: SolverKind) -> Params<T> {
    let mut p = Params::new(T::from_f64(dt));
    p.method = method;
    p.solver.kind = kind;
    p
}

/// Least-squares slope of `log y` against `log x`.
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Asserts a step failed with an error matching `pred` and left the state untouched.
pub fn assert_failed_unchanged<T: Real, const N: usize>(
    before: &[u64],
    ps: &ParticleSet<T, N>,
    result: &Result<StepReport<T>, StepError>,
    pred: impl Fn(&StepError) -> bool,
    what: &str,
) {
    match result {
        Ok(r) => panic!("{what}: expected an error, the step succeeded ({r:?})"),
        Err(e) => assert!(pred(e), "{what}: unexpected error {e:?}"),
    }
    assert_eq!(
        before,
        snapshot(ps).as_slice(),
        "{what}: state changed on error"
    );
}

/// Instantiates a generic test body `$body::<T>()` for f32 and f64 as two tests.
#[macro_export]
macro_rules! both_precisions {
    ($($name:ident => $body:ident;)+) => {
        $(
            mod $name {
                #[test]
                fn f32() {
                    super::$body::<f32>();
                }
                #[test]
                fn f64() {
                    super::$body::<f64>();
                }
            }
        )+
    };
}

/// Per-precision tolerances: `pick::<T>(f32 value, f64 value)`.
pub fn pick<T: Real>(single: f64, double: f64) -> f64 {
    if T::EPSILON.to_f64() > 1e-10 {
        single
    } else {
        double
    }
}

/// True for `f32`.
pub fn is_single<T: Real>() -> bool {
    T::EPSILON.to_f64() > 1e-10
}

/// Bond topology of a test scene.
#[derive(Clone, Debug)]
pub enum Topology {
    Chain,
    Ring,
    Tree(Vec<Option<usize>>),
}

/// A named scene: spheres and how they are bonded (lengths from the positions).
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: &'static str,
    pub spheres: Vec<Sphere>,
    pub topology: Topology,
}

impl Scene {
    /// Particle set and bonds in precision `T`.
    pub fn build<T: Real, const N: usize, const B: usize>(
        &self,
    ) -> (ParticleSet<T, N>, BondSet<T, B>) {
        let ps: ParticleSet<T, N> = particles(&self.spheres);
        let pos = &ps.pos[..ps.len()];
        let bonds = match &self.topology {
            Topology::Chain => BondSet::chain(pos),
            Topology::Ring => BondSet::ring(pos),
            Topology::Tree(parents) => BondSet::tree(pos, parents),
        }
        .expect("valid bonds");
        (ps, bonds)
    }
}

/// An 8-bead polydisperse chain, bent in 3D.
pub fn chain_scene() -> Scene {
    let radii = [1.0, 0.7, 1.3, 1.0, 0.8, 1.2, 1.0, 0.9];
    let dirs = [
        [1.0, 0.2, 0.1],
        [0.6, 0.8, -0.3],
        [0.9, -0.1, 0.5],
        [0.2, -0.9, 0.1],
        [0.8, 0.1, -0.6],
        [0.3, 0.7, 0.6],
        [1.0, -0.3, 0.2],
    ];
    Scene {
        name: "chain",
        spheres: path(&radii, &dirs, 1.2, RHO),
        topology: Topology::Chain,
    }
}

/// A 6-bead polydisperse ring on a tilted circle at irregular angles.
pub fn ring_scene() -> Scene {
    let angles = [0.0f64, 50.0, 115.0, 170.0, 235.0, 300.0];
    let radii = [1.0, 1.2, 0.8, 1.1, 0.9, 1.0];
    let axis = scale([1.0, 1.0, 0.0], 1.0 / 2f64.sqrt());
    let spheres = angles
        .iter()
        .zip(radii)
        .map(|(deg, radius)| {
            let t = deg.to_radians();
            Sphere {
                pos: rotate([3.5 * t.cos(), 3.5 * t.sin(), 0.0], axis, 0.6),
                radius,
                density: RHO,
            }
        })
        .collect();
    Scene {
        name: "ring",
        spheres,
        topology: Topology::Ring,
    }
}

/// An 8-bead branched aggregate: a root with three branches, two of them forked.
pub fn tree_scene() -> Scene {
    let parents = vec![
        None,
        Some(0),
        Some(0),
        Some(0),
        Some(1),
        Some(1),
        Some(2),
        Some(3),
    ];
    let radii = [1.3, 1.0, 1.0, 0.8, 0.9, 1.0, 0.7, 1.1];
    let dirs: [[f64; 3]; 8] = [
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [-0.5, 0.87, 0.0],
        [-0.5, -0.87, 0.2],
        [1.0, 1.0, 0.3],
        [1.0, -1.0, -0.3],
        [-0.3, 1.0, 0.5],
        [0.0, -1.0, -0.5],
    ];
    let mut spheres: Vec<Sphere> = Vec::new();
    for (c, parent) in parents.iter().enumerate() {
        let pos = match *parent {
            None => [0.0; 3],
            Some(p) => {
                let u = scale(dirs[c], 1.0 / norm(dirs[c]));
                add(spheres[p].pos, scale(u, 1.3 * (radii[p] + radii[c])))
            }
        };
        spheres.push(Sphere {
            pos,
            radius: radii[c],
            density: RHO,
        });
    }
    Scene {
        name: "tree",
        spheres,
        topology: Topology::Tree(parents),
    }
}

/// Largest relative bond-length error of the current positions, evaluated in `f64`.
pub fn bond_error<T: Real, const N: usize, const B: usize>(
    ps: &ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
) -> f64 {
    bonds
        .as_slice()
        .iter()
        .map(|b| {
            let r = norm(sub(f64s::<T>(ps.pos[b.i]), f64s::<T>(ps.pos[b.j])));
            let d = b.length.to_f64();
            ((r - d) / d).abs()
        })
        .fold(0.0, f64::max)
}

/// Largest normalised bond-rate error `dt |(r_i - r_j).(v_i - v_j)| / d^2` (the
/// quantity the RATTLE velocity solve drives below its tolerance), in `f64`.
pub fn bond_rate_error<T: Real, const N: usize, const B: usize>(
    ps: &ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    dt: f64,
) -> f64 {
    bonds
        .as_slice()
        .iter()
        .map(|b| {
            let r = sub(f64s::<T>(ps.pos[b.i]), f64s::<T>(ps.pos[b.j]));
            let v = sub(f64s::<T>(ps.vel[b.i]), f64s::<T>(ps.vel[b.j]));
            let d = b.length.to_f64();
            (dot(r, v) * dt).abs() / (d * d)
        })
        .fold(0.0, f64::max)
}

/// `[1.234e-3, ...]` for messages.
pub fn sci(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", items.join(", "))
}
