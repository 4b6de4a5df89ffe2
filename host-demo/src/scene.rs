//! Scene files: a TOML description of a bead system, its fluid and how to integrate it.
//!
//! A scene is parsed in two stages. First the text is deserialized into private "raw"
//! structs that keep the byte span of every value that is later checked
//! ([`toml::Spanned`]); every table refuses unknown keys. Then the raw scene is
//! validated and resolved (defaults filled in, the helix generated, bond lengths
//! measured) into the plain [`Scene`]. Every error, syntactic or physical, carries the
//! line and column of the offending key and displays as `path:line:col: message`.
//!
//! # Tables and keys
//!
//! | table | key | default |
//! | --- | --- | --- |
//! | `[fluid]` | `viscosity` (> 0), `density` (>= 0) | 1, 0 |
//! | `[gravity]` | `acceleration = [x, y, z]` | `[0, 0, -1]` |
//! | `[flow]` | `velocity = [..]`, `vorticity = [..]` (uniform flow plus rigid rotation) | zeros |
//! | `[[particle]]` | `position = [..]` (required), `radius` (required, > 0), `density` (>= 0) | density 4.5 |
//! | `[[bond]]` | `between = [i, j]` (required, 0-based), `length` (> 0) | initial distance |
//! | `[helix]` | `tails`, `head_ratio`, `dhat`, `head_end`, `radius`, `pitch`, `density` | see [`Helix`] |
//! | `[model]` | `hydrodynamics = "rpy"\|"oseen"\|"free-draining"`, `inertia`, `rotation`, `level = "auto"\|"manual"`, `overlap = "reject"\|"allow"` | rpy, false, false, manual, allow |
//! | `[integrator]` | `method` (required), `dt` (required), `duration` (required), `solver = "sweep"\|"newton"`, `tolerance`, `max_iterations`, `precision = "f32"\|"f64"`, `stiffness` | newton, 1e-10, 500, f64, 1e4 |
//! | `[output]` | `every` (steps between trajectory frames, >= 1) | about [`TARGET_FRAMES`] frames |
//!
//! A scene gives either a `[helix]` table or explicit `[[particle]]` (and optionally
//! `[[bond]]`) tables, never both. Units are those of `DESIGN.md` section 4: tail radius
//! 1, viscosity 1, and the default density 4.5 with gravity `[0, 0, -1]` and fluid
//! density 0 gives a lone tail a buoyant weight of `6 pi`, so it settles at speed 1.
//!
//! `overlap` defaults to `"allow"` because the paper's chains have no excluded volume:
//! only the bonds keep beads apart, and non-bonded beads may touch or overlap (the RPY
//! tensors have a regularised form for that). `"reject"` refuses a scene whose initial
//! spheres overlap. A sphere lying wholly inside another is refused either way (the
//! mobility is not defined for it).

use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// Radius of a tail bead of the helix generator: the length unit of the demo scenes.
pub const TAIL_RADIUS: f64 = 1.0;
/// Default particle density: with gravity 1 and fluid density 0, a bead of radius 1
/// has buoyant weight `4/3 pi 4.5 = 6 pi` and settles alone at speed 1 (`eta = 1`).
pub const DEFAULT_DENSITY: f64 = 4.5;
/// Default head-to-tail radius ratio of the helix generator: `2^(1/3)`, a head of twice
/// a tail's volume (the paper's "normal head").
pub const DEFAULT_HEAD_RATIO: f64 = 1.259_921_049_894_873_2;
/// Default helix radius (distance of the tail centres from the vertical axis), in tail
/// radii. The head sits on the axis, so the radius must not exceed the head bond length
/// `dhat (head_ratio + 1)`; 2.0 stays below it for every `dhat >= 1` and
/// `head_ratio >= 1`, so all the paper's cases and the whole phase-diagram grid
/// (`dhat >= 1.05`, `head_ratio >= 1`) use one common helix.
pub const DEFAULT_HELIX_RADIUS: f64 = 2.0;
/// Default helix pitch (rise per turn), in tail radii. With 7, coils one turn apart
/// are 3.5 tail diameters apart (fluid passes between them, they never touch), and
/// for the paper's bond gaps the number of tails per turn is not a whole number (4.5
/// for `dhat = 1.50`, 6.7 for `dhat = 1.05`), so the 24 tails spread round a full ring
/// about the head in top view instead of stacking in a few columns, as in the
/// paper's Figure 1.
pub const DEFAULT_HELIX_PITCH: f64 = 7.0;
/// Number of trajectory frames aimed at when `[output] every` is not given.
pub const TARGET_FRAMES: usize = 200;

/// The scene files of the paper's Figure 1, embedded so that the demo runs from any
/// directory: `(case, file name, text)`.
pub const FIGURE1_SCENES: [(&str, &str, &str); 3] = [
    (
        "a",
        "scenes/figure1a.toml",
        include_str!("../scenes/figure1a.toml"),
    ),
    (
        "b",
        "scenes/figure1b.toml",
        include_str!("../scenes/figure1b.toml"),
    ),
    (
        "c",
        "scenes/figure1c.toml",
        include_str!("../scenes/figure1c.toml"),
    ),
];

// ---------------------------------------------------------------------------------------
// Errors
// ---------------------------------------------------------------------------------------

/// A scene that could not be read, parsed or accepted.
///
/// Displays as `origin:line:col: message` when the error has a place in the file, and
/// as `origin: message` otherwise (for example when the file cannot be read).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// Where the text came from, usually the file's path.
    pub origin: String,
    /// 1-based line and column (in characters) of the offending text, if known.
    pub location: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

impl SceneError {
    /// The 1-based line of the error, if it has one.
    pub fn line(&self) -> Option<usize> {
        self.location.map(|(line, _)| line)
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some((line, col)) => write!(f, "{}:{}:{}: {}", self.origin, line, col, self.message),
            None => write!(f, "{}: {}", self.origin, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// Converts a byte offset in `text` to a 1-based (line, column), columns in characters.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before[line_start..].chars().count() + 1;
    (line, col)
}

/// A semantic error before it is placed in a file: a message and a byte span.
struct Issue {
    span: Option<Range<usize>>,
    message: String,
}

fn issue(span: Range<usize>, message: impl Into<String>) -> Issue {
    Issue {
        span: Some(span),
        message: message.into(),
    }
}

// ---------------------------------------------------------------------------------------
// Public, resolved scene
// ---------------------------------------------------------------------------------------

/// The fluid around the particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Fluid {
    /// Dynamic viscosity `eta` (> 0).
    pub viscosity: f64,
    /// Fluid density (>= 0); enters only the buoyant weight.
    pub density: f64,
}

/// The ambient flow `U_inf(r) = velocity + vorticity x r`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Flow {
    /// Uniform flow velocity.
    pub velocity: [f64; 3],
    /// Angular velocity of the ambient rigid rotation.
    pub vorticity: [f64; 3],
}

/// One rigid sphere.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Particle {
    /// Centre.
    pub position: [f64; 3],
    /// Radius (> 0).
    pub radius: f64,
    /// Material density (>= 0; > 0 for the inertial methods).
    pub density: f64,
}

/// A rigid bond (holonomic distance constraint) between two particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bond {
    /// First particle (0-based index).
    pub i: usize,
    /// Second particle (0-based index), different from `i`.
    pub j: usize,
    /// Centre-to-centre distance the bond holds.
    pub length: f64,
}

/// Which end of the helix the head sits at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum HeadEnd {
    /// Below the first tail (the tails climb the helix above the head).
    #[default]
    Bottom,
    /// Above the first tail (the tails descend the helix below the head).
    Top,
}

/// The helix generator: one head and `tails` tails of radius 1 on a right-handed helix
/// about the vertical `z` axis.
///
/// Bond `k` joins beads `k` and `k + 1` at length `dhat (a_k + a_{k+1})`. The tail
/// centres lie on the helix `(radius cos phi, radius sin phi, pitch phi / 2 pi)` with a
/// constant angular step, solved so that consecutive tails are exactly one bond length
/// apart. The head (bead 0) sits on the axis (`x = y = 0`), inside the ring the tails
/// draw in top view, below the first tail (`head_end = "bottom"`) or above it (`"top"`),
/// at the height that makes its distance to the first tail exactly the head bond length;
/// the head is at the origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Helix {
    /// Number of tail beads (>= 1). Default 24.
    pub tails: usize,
    /// Head radius over tail radius (> 0). Default `2^(1/3)`.
    pub head_ratio: f64,
    /// Bond length over the sum of the two radii (> 0). Default 1.5.
    pub dhat: f64,
    /// Where the head is. Default bottom.
    pub head_end: HeadEnd,
    /// Distance of the tail centres from the axis (> 0). Default
    /// [`DEFAULT_HELIX_RADIUS`].
    pub radius: f64,
    /// Rise per turn (>= 0). Default [`DEFAULT_HELIX_PITCH`].
    pub pitch: f64,
    /// Density of every bead (head and tails alike, as in the paper). Default
    /// [`DEFAULT_DENSITY`].
    pub density: f64,
}

impl Default for Helix {
    fn default() -> Self {
        Helix {
            tails: 24,
            head_ratio: DEFAULT_HEAD_RATIO,
            dhat: 1.5,
            head_end: HeadEnd::Bottom,
            radius: DEFAULT_HELIX_RADIUS,
            pitch: DEFAULT_HELIX_PITCH,
            density: DEFAULT_DENSITY,
        }
    }
}

/// The beads and bonds a generator produced.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chain {
    /// Centres.
    pub positions: Vec<[f64; 3]>,
    /// Radii.
    pub radii: Vec<f64>,
    /// Densities.
    pub densities: Vec<f64>,
    /// Bonds `(i, j, length)`.
    pub bonds: Vec<(usize, usize, f64)>,
}

impl Helix {
    /// Head radius (tail radius is [`TAIL_RADIUS`]).
    pub fn head_radius(&self) -> f64 {
        self.head_ratio * TAIL_RADIUS
    }

    /// Length of the head-to-first-tail bond.
    pub fn head_bond(&self) -> f64 {
        self.dhat * (self.head_radius() + TAIL_RADIUS)
    }

    /// Length of a tail-to-tail bond.
    pub fn tail_bond(&self) -> f64 {
        self.dhat * 2.0 * TAIL_RADIUS
    }

    /// Angular step between consecutive tails: the `dphi` in `(0, pi]` with
    /// `(2 R sin(dphi/2))^2 + (p dphi / 2 pi)^2 = d^2`, found by bisection to the last
    /// bit (the left side increases strictly on that interval).
    pub fn angular_step(&self) -> Result<f64, String> {
        let (r, p, d) = (self.radius, self.pitch, self.tail_bond());
        let chord2 = |x: f64| {
            let h = 2.0 * r * (0.5 * x).sin();
            let v = p * x / (2.0 * std::f64::consts::PI);
            h * h + v * v
        };
        let pi = std::f64::consts::PI;
        if chord2(pi) < d * d {
            return Err(format!(
                "helix too tight: tail bond length {d} exceeds the largest chord \
                 {:.6} of a half turn (radius {r}, pitch {p}); increase radius or pitch",
                chord2(pi).sqrt()
            ));
        }
        let (mut lo, mut hi) = (0.0_f64, pi);
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if chord2(mid) < d * d {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let best = if (chord2(lo) - d * d).abs() <= (chord2(hi) - d * d).abs() {
            lo
        } else {
            hi
        };
        Ok(best)
    }

    /// Checks the numbers (ranges, finiteness) and the geometry.
    pub fn check(&self) -> Result<(), String> {
        if self.tails < 1 {
            return Err("helix needs at least one tail".into());
        }
        for (name, value, min, strict) in [
            ("head_ratio", self.head_ratio, 0.0, true),
            ("dhat", self.dhat, 0.0, true),
            ("radius", self.radius, 0.0, true),
            ("pitch", self.pitch, 0.0, false),
            ("density", self.density, 0.0, false),
        ] {
            check_number(name, value, min, strict)?;
        }
        if self.radius > self.head_bond() {
            return Err(format!(
                "helix radius {} exceeds the head bond length {} = dhat (head_ratio + 1): \
                 the head on the axis cannot reach the first tail; choose radius <= {}",
                self.radius,
                self.head_bond(),
                self.head_bond()
            ));
        }
        self.angular_step().map(|_| ())
    }

    /// Generates the chain: bead 0 is the head, beads `1..=tails` the tails, bonds
    /// `(k, k + 1, dhat (a_k + a_{k+1}))`.
    pub fn generate(&self) -> Result<Chain, String> {
        self.check()?;
        let dphi = self.angular_step()?;
        let sign = match self.head_end {
            HeadEnd::Bottom => 1.0,
            HeadEnd::Top => -1.0,
        };
        let r = self.radius;
        let lift = (self.head_bond().powi(2) - r * r).max(0.0).sqrt();
        let n = self.tails + 1;
        let mut chain = Chain {
            positions: Vec::with_capacity(n),
            radii: Vec::with_capacity(n),
            densities: vec![self.density; n],
            bonds: Vec::with_capacity(self.tails),
        };
        chain.positions.push([0.0, 0.0, 0.0]);
        chain.radii.push(self.head_radius());
        for k in 0..self.tails {
            let phi = sign * (k as f64) * dphi;
            let z = sign * lift + self.pitch * phi / (2.0 * std::f64::consts::PI);
            chain.positions.push([r * phi.cos(), r * phi.sin(), z]);
            chain.radii.push(TAIL_RADIUS);
        }
        for k in 0..self.tails {
            let length = self.dhat * (chain.radii[k] + chain.radii[k + 1]);
            chain.bonds.push((k, k + 1, length));
        }
        Ok(chain)
    }
}

fn check_number(name: &str, value: f64, min: f64, strict: bool) -> Result<(), String> {
    if !value.is_finite() {
        return Err(format!("{name} must be a finite number, not {value}"));
    }
    if strict && value <= min {
        return Err(format!("{name} must be > {min}, not {value}"));
    }
    if !strict && value < min {
        return Err(format!("{name} must be >= {min}, not {value}"));
    }
    Ok(())
}

/// Hydrodynamic interaction model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Hydrodynamics {
    /// Rotne-Prager-Yamakawa grand mobility (with its overlap regularisation).
    #[default]
    #[serde(rename = "rpy")]
    Rpy,
    /// Oseen tensor (not positive definite when beads come close).
    #[serde(rename = "oseen")]
    Oseen,
    /// Self terms only: no hydrodynamic interaction between beads.
    #[serde(rename = "free-draining")]
    FreeDraining,
}

/// Whether the driver may pick the model level itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    /// The driver may choose the cheapest model adequate for the scene.
    Auto,
    /// Use exactly the model written in the scene.
    #[default]
    Manual,
}

/// What to do with initially overlapping (non-nested) spheres.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Overlap {
    /// Refuse the scene.
    Reject,
    /// Accept it (the paper has no excluded volume).
    #[default]
    Allow,
}

/// The physical model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub struct Model {
    /// Hydrodynamic interactions.
    pub hydrodynamics: Hydrodynamics,
    /// Whether particle inertia is resolved.
    pub inertia: bool,
    /// Whether rotations (angular velocities, torques) are resolved.
    pub rotation: bool,
    /// Model-level selection.
    pub level: Level,
    /// Overlap policy.
    pub overlap: Overlap,
}

/// Time integration method (`DESIGN.md` section 2.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// First-order overdamped step with constraint projection (HydroSHAKE).
    #[serde(rename = "overdamped")]
    Overdamped,
    /// Second-order (predictor-corrector) overdamped step.
    #[serde(rename = "overdamped2")]
    Overdamped2,
    /// The paper's inertial HydroRATTLE, explicit drag.
    #[serde(rename = "rattle")]
    Rattle,
    /// Inertial RATTLE with a drag treatment stable at any `dt`.
    #[serde(rename = "rattle-stable")]
    RattleStable,
    /// Hookean springs instead of constraints.
    #[serde(rename = "springs")]
    Springs,
}

impl Method {
    /// Whether the method carries particle momenta (and so needs positive masses).
    pub fn is_inertial(self) -> bool {
        matches!(self, Method::Rattle | Method::RattleStable)
    }
}

/// Constraint solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Solver {
    /// Cyclic SHAKE sweeps, one constraint at a time.
    Sweep,
    /// Newton iteration on the whole constraint Jacobian.
    #[default]
    Newton,
}

/// Floating-point precision of the kernel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Single precision.
    F32,
    /// Double precision.
    #[default]
    F64,
}

/// How to integrate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Integrator {
    /// Method.
    pub method: Method,
    /// Time step (> 0).
    pub dt: f64,
    /// Simulated time (> 0, at least one step).
    pub duration: f64,
    /// Constraint solver.
    pub solver: Solver,
    /// Constraint tolerance (> 0).
    pub tolerance: f64,
    /// Iteration cap of the constraint solver (>= 1).
    pub max_iterations: usize,
    /// Kernel precision.
    pub precision: Precision,
    /// Spring constant for `method = "springs"` (> 0).
    pub stiffness: f64,
}

impl Integrator {
    /// Number of steps: `duration / dt` rounded to the nearest integer (at least 1).
    pub fn steps(&self) -> usize {
        steps_of(self.duration, self.dt)
    }
}

fn steps_of(duration: f64, dt: f64) -> usize {
    ((duration / dt).round() as usize).max(1)
}

/// Trajectory output settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Output {
    /// Steps between trajectory frames (>= 1).
    pub every: usize,
}

/// A fully resolved, validated scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// Fluid properties.
    pub fluid: Fluid,
    /// Gravitational acceleration vector.
    pub gravity: [f64; 3],
    /// Ambient flow.
    pub flow: Flow,
    /// All particles (generated by the helix when `helix` is set).
    pub particles: Vec<Particle>,
    /// All bonds, lengths resolved.
    pub bonds: Vec<Bond>,
    /// The helix generator settings, when the scene used one.
    pub helix: Option<Helix>,
    /// Physical model.
    pub model: Model,
    /// Integrator settings.
    pub integrator: Integrator,
    /// Output settings.
    pub output: Output,
    /// Soft excluded-volume stiffness (`[contact] stiffness`); `None`: spheres may
    /// pass through each other, as in the paper.
    pub contact: Option<f64>,
}

impl Scene {
    /// Reads and parses a scene file; errors name the path, line and column.
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            origin: origin.clone(),
            location: None,
            message: format!("cannot read scene file: {e}"),
        })?;
        Scene::parse(&text, &origin)
    }

    /// Parses scene text; `origin` names it in error messages (usually its path).
    pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| {
            let start = e.span().map_or(0, |s| s.start);
            let mut message = e.message().trim_end().replace('\n', " ");
            // A missing key is reported at its table's header: name the table.
            let header = text
                .get(start..)
                .and_then(|t| t.lines().next())
                .unwrap_or("");
            if message.starts_with("missing field") && header.starts_with('[') {
                message = format!("{message} in {}", header.trim());
            }
            SceneError {
                origin: origin.to_string(),
                location: Some(line_col(text, start)),
                message,
            }
        })?;
        raw.resolve().map_err(|i| SceneError {
            origin: origin.to_string(),
            location: Some(i.span.map_or((1, 1), |s| line_col(text, s.start))),
            message: i.message,
        })
    }

    /// The embedded Figure 1 scenes, parsed: `(case, scene)` for cases a, b, c.
    pub fn figure1() -> Result<Vec<(&'static str, Scene)>, SceneError> {
        FIGURE1_SCENES
            .iter()
            .map(|(case, name, text)| Scene::parse(text, name).map(|s| (*case, s)))
            .collect()
    }

    /// Particle centres.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        self.particles.iter().map(|p| p.position).collect()
    }

    /// Particle radii.
    pub fn radii(&self) -> Vec<f64> {
        self.particles.iter().map(|p| p.radius).collect()
    }

    /// Particle densities.
    pub fn densities(&self) -> Vec<f64> {
        self.particles.iter().map(|p| p.density).collect()
    }

    /// Species names for trajectory files: `H` for the head and `Ta` for tails of a
    /// helix, `P` for every particle of an explicit scene. They are chemical element
    /// symbols because ASE accepts nothing else in the species column (a bare `T`
    /// makes `ase.io.read` fail); OVITO takes any name.
    pub fn species(&self) -> Vec<&'static str> {
        match self.helix {
            Some(_) => (0..self.particles.len())
                .map(|i| if i == 0 { "H" } else { "Ta" })
                .collect(),
            None => vec!["P"; self.particles.len()],
        }
    }
}

// ---------------------------------------------------------------------------------------
// Raw (spanned) form and validation
// ---------------------------------------------------------------------------------------

type S<T> = Option<Spanned<T>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    fluid: Option<RawFluid>,
    gravity: Option<RawGravity>,
    flow: Option<RawFlow>,
    #[serde(rename = "particle")]
    particles: S<Vec<RawParticle>>,
    #[serde(rename = "bond")]
    bonds: S<Vec<RawBond>>,
    helix: S<RawHelix>,
    model: Option<RawModel>,
    integrator: S<RawIntegrator>,
    output: Option<RawOutput>,
    contact: Option<RawContact>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    stiffness: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFluid {
    viscosity: S<f64>,
    density: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGravity {
    acceleration: S<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFlow {
    velocity: S<[f64; 3]>,
    vorticity: S<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParticle {
    position: Spanned<[f64; 3]>,
    radius: Spanned<f64>,
    density: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBond {
    between: Spanned<[usize; 2]>,
    length: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHelix {
    tails: S<usize>,
    head_ratio: S<f64>,
    dhat: S<f64>,
    head_end: Option<HeadEnd>,
    radius: S<f64>,
    pitch: S<f64>,
    density: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    hydrodynamics: Option<Hydrodynamics>,
    inertia: Option<bool>,
    rotation: Option<bool>,
    level: Option<Level>,
    overlap: Option<Overlap>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawIntegrator {
    method: Method,
    dt: Spanned<f64>,
    duration: Spanned<f64>,
    solver: Option<Solver>,
    tolerance: S<f64>,
    max_iterations: S<usize>,
    precision: Option<Precision>,
    stiffness: S<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    every: S<usize>,
}

/// Which bound a number must respect.
#[derive(Clone, Copy)]
enum Bound {
    Positive,
    NonNegative,
}

/// Takes a spanned number (or its default), checks finiteness and bound.
fn number(value: &S<f64>, default: f64, name: &str, bound: Bound) -> Result<f64, Issue> {
    let Some(v) = value else {
        return Ok(default);
    };
    let x = *v.get_ref();
    let bad = match bound {
        _ if !x.is_finite() => Some("a finite number"),
        Bound::Positive if x <= 0.0 => Some("> 0"),
        Bound::NonNegative if x < 0.0 => Some(">= 0"),
        _ => None,
    };
    match bad {
        Some(what) => Err(issue(v.span(), format!("{name} must be {what}, not {x}"))),
        None => Ok(x),
    }
}

fn vector(value: &S<[f64; 3]>, default: [f64; 3], name: &str) -> Result<[f64; 3], Issue> {
    match value {
        None => Ok(default),
        Some(v) => finite_vector(v, name),
    }
}

fn finite_vector(v: &Spanned<[f64; 3]>, name: &str) -> Result<[f64; 3], Issue> {
    let x = *v.get_ref();
    if x.iter().all(|c| c.is_finite()) {
        Ok(x)
    } else {
        Err(issue(
            v.span(),
            format!("{name} must have finite components, not {x:?}"),
        ))
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

impl RawScene {
    fn resolve(self) -> Result<Scene, Issue> {
        let fluid = match &self.fluid {
            None => Fluid {
                viscosity: 1.0,
                density: 0.0,
            },
            Some(f) => Fluid {
                viscosity: number(&f.viscosity, 1.0, "viscosity", Bound::Positive)?,
                density: number(&f.density, 0.0, "fluid density", Bound::NonNegative)?,
            },
        };
        let gravity = match &self.gravity {
            None => [0.0, 0.0, -1.0],
            Some(g) => vector(&g.acceleration, [0.0, 0.0, -1.0], "acceleration")?,
        };
        let flow = match &self.flow {
            None => Flow {
                velocity: [0.0; 3],
                vorticity: [0.0; 3],
            },
            Some(f) => Flow {
                velocity: vector(&f.velocity, [0.0; 3], "velocity")?,
                vorticity: vector(&f.vorticity, [0.0; 3], "vorticity")?,
            },
        };
        let model = match &self.model {
            None => Model::default(),
            Some(m) => Model {
                hydrodynamics: m.hydrodynamics.unwrap_or_default(),
                inertia: m.inertia.unwrap_or(false),
                rotation: m.rotation.unwrap_or(false),
                level: m.level.unwrap_or_default(),
                overlap: m.overlap.unwrap_or_default(),
            },
        };
        let contact = match &self.contact {
            None => None,
            Some(c) => Some(number(
                &c.stiffness,
                0.0,
                "contact stiffness",
                Bound::Positive,
            )?),
        };
        let Some(raw_int) = &self.integrator else {
            return Err(Issue {
                span: None,
                message: "missing table [integrator] (method, dt and duration are required)".into(),
            });
        };
        let integrator = resolve_integrator(raw_int.get_ref())?;
        let every = match self.output.as_ref().and_then(|o| o.every.as_ref()) {
            None => integrator.steps().div_ceil(TARGET_FRAMES).max(1),
            Some(e) if *e.get_ref() == 0 => {
                return Err(issue(e.span(), "every must be >= 1 (steps between frames)"));
            }
            Some(e) => *e.get_ref(),
        };

        let (particles, bonds, helix, body_span) = match (&self.helix, &self.particles) {
            (Some(h), Some(_)) => {
                return Err(issue(
                    h.span(),
                    "give either a [helix] table or [[particle]] tables, not both",
                ));
            }
            (Some(h), None) => {
                if let Some(b) = &self.bonds {
                    return Err(issue(
                        b.span(),
                        "[[bond]] tables cannot be combined with [helix] (the helix makes its own bonds)",
                    ));
                }
                let helix = resolve_helix(h.get_ref())?;
                let chain = helix.generate().map_err(|m| issue(h.span(), m))?;
                let particles = (0..chain.positions.len())
                    .map(|k| Particle {
                        position: chain.positions[k],
                        radius: chain.radii[k],
                        density: chain.densities[k],
                    })
                    .collect();
                let bonds = chain
                    .bonds
                    .iter()
                    .map(|&(i, j, length)| Bond { i, j, length })
                    .collect();
                (particles, bonds, Some(helix), BodySpans::Helix(h.span()))
            }
            (None, Some(ps)) => {
                let (particles, spans) = resolve_particles(ps)?;
                let bonds = resolve_bonds(self.bonds.as_ref(), &particles)?;
                (particles, bonds, None, BodySpans::Particles(spans))
            }
            (None, None) => {
                return Err(Issue {
                    span: None,
                    message:
                        "the scene has no particles: give [[particle]] tables or a [helix] table"
                            .into(),
                });
            }
        };

        check_geometry(&particles, model.overlap, &body_span)?;
        if integrator.method.is_inertial() {
            if let Some(k) = particles.iter().position(|p| p.density <= 0.0) {
                return Err(issue(
                    body_span.density(k),
                    format!(
                        "particle {k} has density {} but the inertial method needs positive masses",
                        particles[k].density
                    ),
                ));
            }
        }

        Ok(Scene {
            fluid,
            gravity,
            flow,
            particles,
            bonds,
            helix,
            model,
            integrator,
            output: Output { every },
            contact,
        })
    }
}

/// Spans of the body's values, to place geometric errors.
enum BodySpans {
    Helix(Range<usize>),
    /// Per particle: span of its position, span of its density (or of its position).
    Particles(Vec<(Range<usize>, Range<usize>)>),
}

impl BodySpans {
    fn position(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v) => v[k].0.clone(),
        }
    }

    fn density(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v) => v[k].1.clone(),
        }
    }
}

fn resolve_integrator(r: &RawIntegrator) -> Result<Integrator, Issue> {
    let dt = number(&Some(r.dt.clone()), 0.0, "dt", Bound::Positive)?;
    let duration = number(&Some(r.duration.clone()), 0.0, "duration", Bound::Positive)?;
    if dt > duration {
        return Err(issue(
            r.dt.span(),
            format!("dt ({dt}) is longer than the duration ({duration})"),
        ));
    }
    if duration / dt > 1e12 {
        return Err(issue(
            r.duration.span(),
            format!("duration / dt = {:e} steps is too many", duration / dt),
        ));
    }
    let max_iterations = match &r.max_iterations {
        None => 500,
        Some(m) if *m.get_ref() == 0 => {
            return Err(issue(m.span(), "max_iterations must be >= 1"));
        }
        Some(m) => *m.get_ref(),
    };
    Ok(Integrator {
        method: r.method,
        dt,
        duration,
        solver: r.solver.unwrap_or_default(),
        tolerance: number(&r.tolerance, 1e-10, "tolerance", Bound::Positive)?,
        max_iterations,
        precision: r.precision.unwrap_or_default(),
        stiffness: number(&r.stiffness, 1e4, "stiffness", Bound::Positive)?,
    })
}

fn resolve_helix(r: &RawHelix) -> Result<Helix, Issue> {
    let d = Helix::default();
    let tails = match &r.tails {
        None => d.tails,
        Some(t) if *t.get_ref() == 0 => return Err(issue(t.span(), "tails must be >= 1")),
        Some(t) => *t.get_ref(),
    };
    Ok(Helix {
        tails,
        head_ratio: number(&r.head_ratio, d.head_ratio, "head_ratio", Bound::Positive)?,
        dhat: number(&r.dhat, d.dhat, "dhat", Bound::Positive)?,
        head_end: r.head_end.unwrap_or_default(),
        radius: number(&r.radius, d.radius, "helix radius", Bound::Positive)?,
        pitch: number(&r.pitch, d.pitch, "pitch", Bound::NonNegative)?,
        density: number(&r.density, d.density, "density", Bound::NonNegative)?,
    })
}

type ParticleSpans = Vec<(Range<usize>, Range<usize>)>;

fn resolve_particles(
    ps: &Spanned<Vec<RawParticle>>,
) -> Result<(Vec<Particle>, ParticleSpans), Issue> {
    if ps.get_ref().is_empty() {
        return Err(issue(ps.span(), "the scene has no particles"));
    }
    let mut particles = Vec::with_capacity(ps.get_ref().len());
    let mut spans = Vec::with_capacity(ps.get_ref().len());
    for p in ps.get_ref() {
        let position = finite_vector(&p.position, "position")?;
        let radius = number(&Some(p.radius.clone()), 0.0, "radius", Bound::Positive)?;
        let density = number(&p.density, DEFAULT_DENSITY, "density", Bound::NonNegative)?;
        particles.push(Particle {
            position,
            radius,
            density,
        });
        let dspan = p.density.as_ref().map_or(p.position.span(), |d| d.span());
        spans.push((p.position.span(), dspan));
    }
    Ok((particles, spans))
}

fn resolve_bonds(
    bonds: Option<&Spanned<Vec<RawBond>>>,
    particles: &[Particle],
) -> Result<Vec<Bond>, Issue> {
    let Some(bonds) = bonds else {
        return Ok(Vec::new());
    };
    let n = particles.len();
    let mut out: Vec<Bond> = Vec::with_capacity(bonds.get_ref().len());
    for b in bonds.get_ref() {
        let [i, j] = *b.between.get_ref();
        if i >= n || j >= n {
            return Err(issue(
                b.between.span(),
                format!(
                    "bond between [{i}, {j}]: particle index out of range (the scene has {n} particles, indices 0..={})",
                    n - 1
                ),
            ));
        }
        if i == j {
            return Err(issue(
                b.between.span(),
                format!("bond between [{i}, {j}] joins a particle to itself"),
            ));
        }
        if out
            .iter()
            .any(|o| (o.i == i && o.j == j) || (o.i == j && o.j == i))
        {
            return Err(issue(
                b.between.span(),
                format!("bond between [{i}, {j}] is given twice"),
            ));
        }
        let initial = distance(particles[i].position, particles[j].position);
        let length = number(&b.length, initial, "bond length", Bound::Positive)?;
        out.push(Bond { i, j, length });
    }
    Ok(out)
}

fn check_geometry(
    particles: &[Particle],
    overlap: Overlap,
    spans: &BodySpans,
) -> Result<(), Issue> {
    for j in 0..particles.len() {
        for i in 0..j {
            let (p, q) = (&particles[i], &particles[j]);
            let s = distance(p.position, q.position);
            if s <= (p.radius - q.radius).abs() {
                return Err(issue(
                    spans.position(j),
                    format!(
                        "particle {j} and particle {i} are nested (centre distance {s}, radii {} and {}): one sphere inside another is not a valid configuration",
                        q.radius, p.radius
                    ),
                ));
            }
            if overlap == Overlap::Reject && s < p.radius + q.radius {
                return Err(issue(
                    spans.position(j),
                    format!(
                        "particle {j} overlaps particle {i} (centre distance {s} < {}), and [model] overlap = \"reject\"",
                        p.radius + q.radius
                    ),
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n\n[integrator]\nmethod = \"overdamped\"\ndt = 0.01\nduration = 1\n";

    #[test]
    fn line_col_counts_lines_and_characters() {
        let t = "ab\nçd\nx";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 3), (2, 1));
        assert_eq!(line_col(t, 5), (2, 2)); // after the two-byte 'ç'
        assert_eq!(line_col(t, 100), (3, 2));
    }

    #[test]
    fn minimal_scene_gets_defaults() {
        let s = Scene::parse(MINIMAL, "m.toml").unwrap();
        assert_eq!(s.fluid.viscosity, 1.0);
        assert_eq!(s.fluid.density, 0.0);
        assert_eq!(s.gravity, [0.0, 0.0, -1.0]);
        assert_eq!(s.particles[0].density, DEFAULT_DENSITY);
        assert_eq!(s.model, Model::default());
        assert_eq!(s.integrator.solver, Solver::Newton);
        assert_eq!(s.integrator.tolerance, 1e-10);
        assert_eq!(s.integrator.max_iterations, 500);
        assert_eq!(s.integrator.precision, Precision::F64);
        assert_eq!(s.integrator.stiffness, 1e4);
        assert_eq!(s.integrator.steps(), 100);
        assert_eq!(s.output.every, 1);
        assert_eq!(s.species(), vec!["P"]);
    }

    #[test]
    fn default_density_settles_a_lone_tail_at_unit_speed() {
        let weight = 4.0 / 3.0 * std::f64::consts::PI * DEFAULT_DENSITY;
        assert!((weight - 6.0 * std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn default_every_aims_at_200_frames() {
        let text = MINIMAL.replace("duration = 1", "duration = 400");
        let s = Scene::parse(&text, "m.toml").unwrap();
        assert_eq!(s.integrator.steps(), 40_000);
        assert_eq!(s.output.every, 200);
    }

    #[test]
    fn semantic_error_points_at_the_key() {
        let text = MINIMAL.replace("radius = 1", "radius = -1");
        let e = Scene::parse(&text, "m.toml").unwrap_err();
        assert_eq!(e.location, Some((3, 10)));
        assert!(e.to_string().starts_with("m.toml:3:10: radius must be > 0"));
    }

    #[test]
    fn unknown_key_is_an_error_with_its_line() {
        let text = MINIMAL.replace("radius = 1", "radius = 1\ncolour = 2");
        let e = Scene::parse(&text, "m.toml").unwrap_err();
        assert_eq!(e.line(), Some(4), "{e}");
        assert!(e.message.contains("colour"), "{e}");
    }

    #[test]
    fn helix_default_geometry_is_exact() {
        let h = Helix::default();
        let c = h.generate().unwrap();
        assert_eq!(c.positions.len(), 25);
        for &(i, j, d) in &c.bonds {
            let s = distance(c.positions[i], c.positions[j]);
            assert!((s - d).abs() < 1e-12, "bond {i}-{j}: {s} vs {d}");
        }
        // Head at the bottom, on the axis.
        assert_eq!(c.positions[0], [0.0, 0.0, 0.0]);
        assert!(c.positions[1..].iter().all(|p| p[2] > 0.0));
    }

    #[test]
    fn helix_head_at_top_is_above_every_tail() {
        let h = Helix {
            head_end: HeadEnd::Top,
            ..Helix::default()
        };
        let c = h.generate().unwrap();
        assert!(c.positions[1..].iter().all(|p| p[2] < 0.0));
        let s = distance(c.positions[0], c.positions[1]);
        assert!((s - h.head_bond()).abs() < 1e-12);
    }

    #[test]
    fn helix_too_wide_for_the_head_bond_is_refused() {
        let h = Helix {
            radius: 3.0,
            dhat: 1.05,
            ..Helix::default()
        };
        assert!(h.generate().unwrap_err().contains("head bond"));
    }

    #[test]
    fn helix_too_tight_is_refused() {
        let h = Helix {
            radius: 1.0,
            pitch: 0.5,
            dhat: 1.5,
            head_ratio: 2.0,
            ..Helix::default()
        };
        assert!(h.generate().unwrap_err().contains("too tight"));
    }
}
