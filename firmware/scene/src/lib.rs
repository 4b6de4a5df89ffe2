//! The paper's Figure 1 case (c) chain and a digest of its positions' bits, written
//! once and used by the Cortex-M firmware, the host check and the C interface, so that
//! "host and target give the same bits" compares like with like.
//!
//! The chain follows `host/scenes/figure1c.toml`: a head of radius 2 (bead 0) and
//! 24 tails of radius 1, density 4.5, bonds of length `1.05 (a_i + a_j)`, the tails on
//! a right-handed helix of radius 2 and pitch 7 about the vertical axis, the head on the
//! axis below the first tail. The geometry is computed in `f64` with `libm` (the same
//! code on every target) and rounded once to the run's precision.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(feature = "alloc")]
extern crate alloc;

use core::fmt::{self, Write};

use hydrorattle::glam::Vec3;
use hydrorattle::{
    Bond, BondSet, Brownian, Drift, Hydro, Lanczos, Method, Noise, NoiseSqrt, Params, Particle,
    ParticleSet, Real, SoftContact, Solver, SolverKind, StepError, StepReport, Workspace, step,
};

/// Beads: one head and 24 tails.
pub const N: usize = 25;
/// Bonds of the chain.
pub const B: usize = N - 1;
/// Steps the firmware and the host check run.
pub const STEPS: u32 = 200;
/// Head radius over tail radius (case c: "big head").
pub const HEAD_RADIUS: f64 = 2.0;
/// Bond length over the sum of the two radii.
pub const DHAT: f64 = 1.05;
/// Tail centres' distance from the vertical axis.
pub const HELIX_RADIUS: f64 = 2.0;
/// Rise per turn of the helix.
pub const HELIX_PITCH: f64 = 7.0;
/// Density of every bead.
pub const DENSITY: f64 = 4.5;
/// Time step of the scene.
pub const DT: f64 = 0.005;
/// Soft-contact stiffness of the scene (`[contact] stiffness`).
pub const CONTACT_STIFFNESS: f64 = 1000.0;

/// Thermal energy of the Brownian run (the C example's: `ffi/examples/chain.c`).
pub const KT: f64 = 0.5;
/// Seed of the Brownian run's generator (the C example's).
pub const SEED: u64 = 7;

/// The runs the firmware has a binary for: name, method, rotation resolved, thermal
/// noise at [`KT`] (midpoint drift, generator seeded with [`SEED`]).
pub const RUNS: [(&str, Method, bool, bool); 7] = [
    ("overdamped", Method::Overdamped, false, false),
    ("overdamped2", Method::Overdamped2, false, false),
    ("rattle", Method::Rattle, false, false),
    ("stable", Method::RattleStable, false, false),
    ("stable_rotation", Method::RattleStable, true, false),
    ("springs", Method::Springs, false, false),
    ("brownian", Method::Overdamped, false, true),
];

/// The chain's geometry in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Helix {
    /// Bead centres.
    pub pos: [[f64; 3]; N],
    /// Bead radii.
    pub radius: [f64; N],
    /// Bond lengths (bond `k` joins beads `k` and `k + 1`).
    pub length: [f64; B],
}

/// The scene's helix in the kernel's terms (the host scenes build theirs from the same
/// function, [`hydrorattle::helix`]).
pub const SCENE_HELIX: hydrorattle::helix::Helix = hydrorattle::helix::Helix {
    tails: B,
    head_ratio: HEAD_RADIUS,
    dhat: DHAT,
    radius: HELIX_RADIUS,
    pitch: HELIX_PITCH,
    head_end: hydrorattle::helix::HeadEnd::Bottom,
};

/// The chain with `tails` tails (the unused entries are zero). `None` when the helix
/// cannot be built (fewer than one tail, or more than `N - 1`).
pub fn helix(tails: usize) -> Option<Helix> {
    if tails > B {
        return None;
    }
    let h = hydrorattle::helix::Helix {
        tails,
        ..SCENE_HELIX
    };
    let mut pos = [[0.0; 3]; N];
    let mut radius = [0.0; N];
    let mut length = [0.0; B];
    for (k, p) in h.positions().ok()?.enumerate() {
        pos[k] = p;
        radius[k] = h.bead_radius(k);
    }
    for (k, l) in length.iter_mut().enumerate().take(tails) {
        *l = h.bond_length(k);
    }
    Some(Helix {
        pos,
        radius,
        length,
    })
}

/// Fills `ps` (which must be empty) with the chain and returns its bonds.
pub fn chain<T: Real>(ps: &mut ParticleSet<T, N>) -> Result<BondSet<T, B>, StepError> {
    chain_from(&helix(B).ok_or(StepError::StateLength)?, ps)
}

/// [`chain`] from a geometry computed beforehand (the firmware's comes from its build
/// script, so that no `f64` trigonometry is linked into it).
pub fn chain_from<T: Real>(
    h: &Helix,
    ps: &mut ParticleSet<T, N>,
) -> Result<BondSet<T, B>, StepError> {
    let Helix {
        pos,
        radius,
        length,
    } = h;
    for (c, &a) in pos.iter().zip(radius) {
        let p = Particle::new(T::v3_from(*c), T::from_f64(a), T::from_f64(DENSITY));
        ps.push(p).map_err(|(_, e)| e)?;
    }
    let mut bonds = BondSet::new();
    for (k, &d) in length.iter().enumerate() {
        let b = Bond {
            i: k,
            j: k + 1,
            length: T::from_f64(d),
        };
        bonds.push(b, N).map_err(|(_, e)| e)?;
    }
    Ok(bonds)
}

/// The scene's parameters for `method` (rotation resolved or not): `dt` 0.005, RPY,
/// gravity `(0, 0, -1)`, Newton with the precision's default tolerance and a cap of
/// 500, overlapping spheres allowed (the scene's soft contact keeps them apart); with
/// `brownian`, thermal noise at [`KT`] with the midpoint drift, its square root by
/// [`NOISE_SQRT`].
pub fn params<T: Real>(method: Method, rotation: bool, brownian: bool) -> Params<T> {
    let mut p = Params::new(T::from_f64(DT));
    p.method = method;
    p.rotation = rotation;
    p.solver.kind = SolverKind::Newton;
    p.solver.max_iterations = 500;
    p.allow_overlap = true;
    if brownian {
        p.brownian = Some(Brownian::new(T::from_f64(KT)));
        p.noise_sqrt = NOISE_SQRT;
    }
    p
}

/// The thermal runs' square root of the mobility: Cholesky, what the kernel's default
/// [`NoiseSqrt::Auto`] picks at [`N`] beads (a test checks it), named so that the
/// firmware does not link the Lanczos path `Auto` would choose between at run time.
pub const NOISE_SQRT: NoiseSqrt = NoiseSqrt::Cholesky;

/// [`params`] in `f32` as a constant (a test checks that the two agree). Firmware keeps
/// it in a `static`: the compiler then sees the method, drops the other integrators
/// and inlines the step (38 KB of flash instead of 87 KB for Overdamped).
pub const fn params_f32(method: Method, rotation: bool, brownian: bool) -> Params<f32> {
    let mut p = deterministic_f32(method, rotation);
    if brownian {
        p.brownian = Some(Brownian {
            temperature: KT as f32,
            drift: Drift::Midpoint,
        });
        p.noise_sqrt = NOISE_SQRT;
    }
    p
}

const fn deterministic_f32(method: Method, rotation: bool) -> Params<f32> {
    Params {
        dt: DT as f32,
        viscosity: 1.0,
        fluid_density: 0.0,
        gravity: Vec3::new(0.0, 0.0, -1.0),
        flow_velocity: Vec3::ZERO,
        vorticity: Vec3::ZERO,
        hydro: Hydro::Rpy,
        method,
        rotation,
        matrix_free: false,
        solver: Solver {
            kind: SolverKind::Newton,
            tolerance: 1e-5,
            max_iterations: 500,
        },
        allow_overlap: true,
        spring_stiffness: 1e3,
        fene: None,
        stability_guard: false,
        brownian: None,
        // The kernel's defaults (no noise here; the thermal runs set `NOISE_SQRT`).
        noise_sqrt: NoiseSqrt::Auto,
        lanczos: Lanczos {
            tolerance: 1e-3,
            max_iterations: 64,
        },
        contacts: None,
        wall: None,
        slit: None,
        periodic: None,
        compact_products: false,
        // The kernel's f32 default: the inertial methods' tensions from the displacements.
        resolve_tensions: true,
        pse: None,
        near: None,
    }
}

/// The scene's soft contact.
pub fn contact<T: Real>() -> SoftContact<T> {
    SoftContact {
        stiffness: T::from_f64(CONTACT_STIFFNESS),
    }
}

/// The bits of a float, for the digest.
pub trait Bits: Real {
    /// Little-endian bytes of `to_bits()` fed to `f`.
    fn feed(self, f: &mut impl FnMut(u8));
}

impl Bits for f32 {
    fn feed(self, f: &mut impl FnMut(u8)) {
        self.to_bits().to_le_bytes().into_iter().for_each(f);
    }
}

impl Bits for f64 {
    fn feed(self, f: &mut impl FnMut(u8)) {
        self.to_bits().to_le_bytes().into_iter().for_each(f);
    }
}

/// FNV-1a (64 bit) over the little-endian bytes of `to_bits()` of every position
/// component, bead by bead, x, y, z.
pub fn digest<T: Bits>(pos: &[T::V3]) -> u64 {
    fnv(pos.iter().flat_map(|&v| T::xyz(v)))
}

/// [`digest`] of positions held as `[x, y, z]` triples (as C callers hold them).
pub fn digest_triples<T: Bits>(pos: &[[T; 3]]) -> u64 {
    fnv(pos.iter().flatten().copied())
}

fn fnv<T: Bits>(components: impl Iterator<Item = T>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |b: u8| {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    for c in components {
        c.feed(&mut eat);
    }
    h
}

/// What a run produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome<T> {
    /// Steps done.
    pub steps: u32,
    /// [`digest`] of the final positions.
    pub digest: u64,
    /// The last step's report.
    pub report: StepReport<T>,
}

/// A failed run: the step that failed (0-based) and its error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    /// The step.
    pub step: u32,
    /// The error.
    pub error: StepError,
}

/// Runs `steps` steps of the scene from the chain in `ps`; `each` is called around
/// every step (`true` before, `false` after), for timing. A thermal run (`p.brownian`)
/// draws from a generator seeded with [`SEED`], unless `ps` already carries one.
pub fn run<T: Bits>(
    ps: &mut ParticleSet<T, N>,
    bonds: &BondSet<T, B>,
    p: &Params<T>,
    ws: &mut Workspace<'_, T>,
    steps: u32,
    mut each: impl FnMut(bool),
) -> Result<Outcome<T>, Failure> {
    let mut contact = contact::<T>();
    let mut report = StepReport::default();
    if p.brownian.is_some() && ps.noise.is_none() {
        ps.noise = Some(Noise::new(SEED));
    }
    for s in 0..steps {
        each(true);
        let r = step(ps, bonds, p, ws, &mut contact);
        each(false);
        report = r.map_err(|error| Failure { step: s, error })?;
    }
    Ok(Outcome {
        steps,
        digest: digest::<T>(&ps.pos[..ps.len()]),
        report,
    })
}

/// A float as its bits in hex (no float formatting: it would cost firmware flash).
pub struct Hex<T>(pub T);

impl fmt::Display for Hex<f32> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#010x}", self.0.to_bits())
    }
}

impl fmt::Display for Hex<f64> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#018x}", self.0.to_bits())
    }
}

/// The line both the firmware and the host check print for a run; CI compares them.
/// A thermal run adds `kT=` (its bits) and `seed=`.
pub fn summary<T: Bits>(
    w: &mut impl Write,
    p: &Params<T>,
    outcome: &Result<Outcome<T>, Failure>,
) -> fmt::Result
where
    Hex<T>: fmt::Display,
{
    let bits = core::mem::size_of::<T>() * 8;
    write!(
        w,
        "figure1c f{bits} {:?} rotation={} ",
        p.method, p.rotation as u8
    )?;
    if let Some(b) = p.brownian {
        // The seed through `decimal`: core's `u64` formatting would link a software
        // 64-bit division on 32-bit Arm.
        write!(w, "kT={} seed=", Hex(b.temperature))?;
        decimal(w, SEED)?;
        w.write_str(" ")?;
    }
    match outcome {
        Ok(o) => writeln!(
            w,
            "steps={} digest={:016x} iterations={} velocity_iterations={} residual={} max_tension={}",
            o.steps,
            o.digest,
            o.report.iterations,
            o.report.velocity_iterations,
            Hex(o.report.residual),
            Hex(o.report.max_tension)
        ),
        Err(e) => {
            // `write_str`, not `{}`: a `&str` through `{}` links core's padding code.
            write!(w, "failed at step {}: ", e.step)?;
            w.write_str(e.error.kind())?;
            if let Some(what) = e.error.detail() {
                w.write_str(" ")?;
                w.write_str(what)?;
            }
            w.write_str("\n")
        }
    }
}

/// `n` in decimal, as `{}` writes it, through [`div_rem`] (the firmware's cost line:
/// core's `u64` formatting links a software 64-bit division on 32-bit Arm). The
/// leading digits first, by recursion (at most 19 deep): a digit buffer's bound would
/// let the compiler unroll the loop 20 times.
#[inline(never)]
pub fn decimal(w: &mut impl Write, n: u64) -> fmt::Result {
    const DIGITS: [&str; 10] = ["0", "1", "2", "3", "4", "5", "6", "7", "8", "9"];
    let (rest, digit) = div_rem(n, 10);
    if rest != 0 {
        decimal(w, rest)?;
    }
    w.write_str(DIGITS[digit as usize])
}

/// `(n / d, n % d)` as `u64` division gives them, for a divisor of 32 bits (`d = 0`
/// divides by 1): the high word by the 32-bit divide, the low word bit by bit with
/// shifts and compares, so that 32-bit Arm links no software 64-bit division. Out of
/// line, and the bit loop ends on a marker bit rather than a count, so that the
/// compiler keeps it one small loop rather than 32 copies (flash).
#[inline(never)]
pub fn div_rem(n: u64, d: u32) -> (u64, u32) {
    let (d, hi) = (d.max(1), (n >> 32) as u32);
    // The remainder stays below `d`: shifted once, it fits 33 bits.
    let (q_hi, mut r) = (u64::from(hi / d), u64::from(hi % d));
    let d = u64::from(d);
    // The low word's bits, most significant first, above a marker bit that reaches the
    // top once all 32 are out.
    const DONE: u64 = 1 << 63;
    let mut bits = (n << 32) | (1 << 31);
    let mut q_lo = 0u64;
    while bits != DONE {
        r = (r << 1) | (bits >> 63);
        bits <<= 1;
        q_lo <<= 1;
        if r >= d {
            r -= d;
            q_lo |= 1;
        }
    }
    ((q_hi << 32) | q_lo, r as u32)
}

/// The summary lines of the [`RUNS`] named in `only` (all when empty), computed on
/// this machine: what the firmware must print.
#[cfg(feature = "alloc")]
pub fn host_summaries(only: &[&str]) -> alloc::string::String {
    use hydrorattle::Layout;
    use hydrorattle_heap::Buffers;
    let mut out = alloc::string::String::new();
    for (name, method, rotation, brownian) in RUNS {
        if !only.is_empty() && !only.contains(&name) {
            continue;
        }
        let mut ps = ParticleSet::<f32, N>::new();
        let outcome = chain(&mut ps)
            .map_err(|error| Failure { step: 0, error })
            .and_then(|bonds| {
                let p = params::<f32>(method, rotation, brownian);
                let mut store = Buffers::<f32>::new(Layout::for_params(&p, N, bonds.len()));
                run(&mut ps, &bonds, &p, &mut store.workspace(), STEPS, |_| {})
            });
        // Writing to a String cannot fail.
        let _ = summary(
            &mut out,
            &params::<f32>(method, rotation, brownian),
            &outcome,
        );
    }
    out
}
