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
//! | `[flow]` | `velocity = [..]`, `vorticity = [..]` (uniform flow plus rigid rotation; at most [`MAX_TURN_PER_STEP`] radians a step: `\|vorticity\| dt <= 1`) | zeros |
//! | `[[particle]]` | `position = [..]` (required), `radius` (required, > 0), `density` (>= 0), `velocity = [..]`, `angular_velocity = [..]`, `species` (a type name), `fixed` (`true`: pinned where it is) | density 4.5, at rest, one species per radius and density |
//! | `[[bond]]` | `between = [i, j]` (required, 0-based), `length` (> 0; >= 0 with `method = "springs"`: a spring's rest length) | initial distance |
//! | `[helix]` | `tails`, `head_ratio`, `dhat`, `head_end`, `radius`, `pitch`, `density` | see [`Helix`] |
//! | `[model]` | `hydrodynamics = "rpy"\|"oseen"\|"free-draining"`, `inertia`, `rotation`, `level = "auto"\|"manual"`, `overlap = "reject"\|"allow"` | rpy, false, false, manual, reject |
//! | `[integrator]` | `method` (required), `dt` (required), `duration` (required), `solver = "auto"\|"sweep"\|"newton"\|"krylov"`, `tolerance`, `max_iterations`, `precision = "f32"\|"f64"`, `stiffness`, `fene` (FENE maximum extension `Q0` > 0, springs only; every bond must start shorter), `matrix_free` (never store the mobility: `O(N)` storage; overdamped, overdamped2 or springs, level manual), `compact_products` (the Krylov constraint products from an `f32` copy of the mobility, where the kernel takes it) | auto, 1e-10, 500, f64, 1e4, none (Hookean), false, false |
//! | `[output]` | `every` (steps between trajectory frames, >= 1) | about [`TARGET_FRAMES`] frames |
//! | `[brownian]` | `temperature` (kT, >= 0; > 0 needs `method = "overdamped"`, `"springs"` or `"rattle-stable"`, level manual), `seed` (>= 0), `drift = "midpoint"\|"uncorrected"` | 0, 1, midpoint |
//! | `[wall]` | `height` (required, finite): a no-slip plane `z = height` below every sphere (`method = "overdamped"` or `"overdamped2"`, level manual; see [`Wall`]) | no wall |
//! | `[slit]` | `floor`, `ceiling` (required, finite, the ceiling above the floor): two no-slip planes around every sphere, their mobility by superposition (`method = "overdamped"` or `"overdamped2"`, level manual, no `[wall]`, `[box]` or `[near_field]`; see [`Slit`], `docs/GEOMETRY.md`) | no slit |
//! | `[free_space]` | `method = "dense"\|"fast"\|"auto"`, `tolerance` (`1e-10` to `0.1`): how the mobility in open fluid is applied; `"fast"` is the `O(N log N)` product; `"auto"` the path a measured cost model picks when the run starts (`free_cost`); `reweigh`: on the fast product, weigh it against the pair sums before every step (`free_reweigh`; default on under `"auto"`) (overdamped, overdamped2 or springs, level manual, RPY, no wall, box or near field; its run is matrix-free; see [`FreeSpace`]) | dense, 1e-4 |
//! | `[box]` | `size = [Lx, Ly, Lz]` (required unless `[suspension]` sets it; finite, > 0), `method = "ewald"\|"pse"\|"auto"`, `tolerance` (`1e-12` to `0.1`): a periodic box (see [`PeriodicBox`]) | no box; auto, 1e-6 |
//! | `[suspension]` | `count` (required, >= 1), `fraction` (required, `0 < phi <=` [`MAX_FRACTION`]), `radius`, `polydispersity` (`0 <= p < 1`), `density`, `seed`: spheres placed at random in a cubic box (see [`Suspension`]) | 1, 0, 4.5, 1 |
//! | `[cloud]` | `count` (required, >= 1), `cloud_radius` (required, > 0), `radius`, `polydispersity` (`0 <= p < 1`), `density`, `centre = [x, y, z]`, `seed`: spheres placed at random, without overlap, in a ball in open fluid (see [`Cloud`]) | 1, 0, 4.5, origin, 1 |
//! | `[floor]` | `radius` (> 0), `density` (>= 0): a pinned square lattice under the `[suspension]` (see [`Floor`]) | the suspension's radius and density |
//! | `[near_field]` | `cutoff` (>= 0), `wall_cutoff` (>= 0), `min_gap` (> 0), in radii: Stokesian dynamics' near field on the RPY far field (`hydrodynamics = "rpy"`, level manual, `method = "overdamped"` or `"overdamped2"`, free space or `[wall]`; see [`NearField`], `docs/NEAR.md`) | no near field; 4, 4, 1e-3 |
//!
//! A scene gives one of a `[helix]` table, a `[suspension]` table (which needs a
//! `[box]` table, without `size`), a `[cloud]` table or explicit `[[particle]]` (and optionally
//! `[[bond]]`) tables. Units are those of `docs/MODEL.md#units`: tail radius
//! 1, viscosity 1, and the default density 4.5 with gravity `[0, 0, -1]` and fluid
//! density 0 gives a lone tail a buoyant weight of `6 pi`, so it settles at speed 1.
//!
//! A scene whose step storage would exceed a limit ([`crate::sizing`]) is refused from
//! its counts, before the helix is generated or any pair checked, at the value that set
//! the count.
//!
//! `overlap` is about t = 0 and defaults to `"reject"`: spheres that overlap at the
//! start are almost always a typing error, so such a scene is refused at the line of
//! the later sphere unless it says `overlap = "allow"`. During the run spheres may come
//! to overlap whatever the setting (the paper's chains have no excluded volume; the RPY
//! tensors have a regularised form for it; `[contact]` adds hard or soft excluded volume). A sphere
//! lying wholly inside another is refused either way (the mobility is not defined for
//! it).

pub mod auto;
mod beads;
mod bodies;
pub mod box_cost;
#[cfg(test)]
mod box_cost_tests;
#[cfg(test)]
mod box_tests;
mod cloud;
mod contact;
mod error;
mod floor;
#[cfg(test)]
mod floor_tests;
pub mod free_cost;
#[cfg(test)]
mod free_cost_tests;
pub mod free_noise;
#[cfg(test)]
mod free_noise_tests;
#[cfg(test)]
mod free_pick_tests;
pub mod free_reweigh;
#[cfg(test)]
mod free_reweigh_tests;
mod free_space;
mod helix;
mod kernel;
mod model;
pub mod names;
mod near;
mod periodic;
mod precision;
mod raw;
mod resolve;
pub mod sizing;
mod slit;
mod suspension;
#[cfg(test)]
mod tests;
mod thermal;
mod wall;
mod write;

pub use beads::{Beads, BuildError, beads, bonds, params, pins};
pub use box_cost::pse_pays;
pub use cloud::Cloud;
pub use contact::{Contact, DEFAULT_CONTACTS_PER_PARTICLE, SOFT_DT, SOFT_STIFFNESS};
pub use error::{SceneError, line_col};
pub use floor::{Floor, slab_fraction};
pub use free_space::{DEFAULT_FREE_TOLERANCE, FreeMethod, FreeSpace};
pub use helix::{Chain, HeadEnd, Helix};
pub use model::{
    Bond, Flow, Fluid, Hydrodynamics, Integrator, Level, Method, Model, Output, Overlap, Particle,
    Precision, Solver,
};
pub use near::NearField;
pub use periodic::{BoxMethod, DEFAULT_BOX_TOLERANCE, PeriodicBox, PseUnsupported, pse_fits};
pub use resolve::MAX_TURN_PER_STEP;
pub use slit::Slit;
pub use suspension::{GAP, MAX_FRACTION, Suspension, TRIALS_PER_SPHERE};
pub use thermal::{DEFAULT_SEED, Drift, Sqrt, Thermal};
pub use wall::Wall;

use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::Path;
use toml::Spanned;
use toml::de::DeTable;

use crate::output::Topology;
use crate::sizing::{DEFAULT_LIMIT, Limits};
use raw::RawScene;

/// Radius of a tail bead of the helix generator: the length unit of the demo scenes.
pub const TAIL_RADIUS: f64 = hydrorattle::helix::TAIL_RADIUS;
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
/// Largest `max_iterations`: it bounds the constraint work of one step (a Newton
/// iteration is a factorisation of the bonds' Jacobian, a sweep a pass over the bonds).
/// 10 000 is 20 times the default 500, more than a converging solve takes; past it a
/// tolerance the solve cannot reach (`tolerance = 1e-16`) would hold one step for
/// hours instead of ending it with a convergence failure.
pub const MAX_ITERATIONS: usize = 10_000;
/// Number of trajectory frames aimed at when `[output] every` is not given.
pub const TARGET_FRAMES: usize = 200;

/// The scene files of the paper's Figure 1, embedded so that the demo runs from any
/// directory: `(case, file name, text)`. The files live with the library's other
/// shipped scenes (`host/scenes/`), where users find and copy them.
pub const FIGURE1_SCENES: [(&str, &str, &str); 3] = [
    (
        "a",
        "scenes/figure1a.toml",
        include_str!("../../scenes/figure1a.toml"),
    ),
    (
        "b",
        "scenes/figure1b.toml",
        include_str!("../../scenes/figure1b.toml"),
    ),
    (
        "c",
        "scenes/figure1c.toml",
        include_str!("../../scenes/figure1c.toml"),
    ),
];

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
    /// Excluded volume (`[contact]`: soft repulsion or hard contacts); `None`: spheres
    /// may pass through each other, as in the paper.
    pub contact: Option<Contact>,
    /// Thermal noise (`[brownian]`); `None`: deterministic.
    pub brownian: Option<Thermal>,
    /// A no-slip plane wall below the spheres (`[wall]`); `None`: unbounded fluid.
    pub wall: Option<Wall>,
    /// A slit between two no-slip plane walls (`[slit]`); `None`: no slit. Left out of
    /// the JSON when `None`, so that a run without one records what it did before.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slit: Option<Slit>,
    /// A periodic box (`[box]`); `None`: unbounded fluid. Left out of the JSON when
    /// `None`, so that a run without a box records what it did before boxes existed.
    #[serde(rename = "box", skip_serializing_if = "Option::is_none")]
    pub periodic: Option<PeriodicBox>,
    /// The suspension generator's settings, when the scene used one (`[suspension]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub suspension: Option<Suspension>,
    /// The cloud generator's settings, when the scene used one (`[cloud]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cloud: Option<Cloud>,
    /// The pinned floor under the suspension, when the scene lays one (`[floor]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor: Option<Floor>,
    /// The pinned spheres (ascending indices): held at their positions by the kernel's
    /// pin rows (`fixed = true` on a `[[particle]]`, or the `[floor]`'s spheres).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pinned: Vec<usize>,
    /// How the free-space mobility is applied (`[free_space]`); `None`: `"dense"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub free_space: Option<FreeSpace>,
    /// Stokesian dynamics' near field (`[near_field]`); `None`: the far field alone.
    /// Left out of the JSON when `None`, as the box is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_field: Option<NearField>,
    /// Species (type name) of each particle: `head` and `tail` for a helix; the
    /// `species` key, or one name per distinct radius and density, for explicit
    /// particles. The generators' names are borrowed: a sweep resolves a scene per
    /// point, and a name allocated per bead was half the cost of its scenes (many
    /// small allocations freed between larger ones: glibc's slow path).
    pub species: Vec<Cow<'static, str>>,
}

impl Scene {
    /// Reads and parses a scene file; errors name the path, line and column. Refuses a
    /// scene whose step storage would exceed [`DEFAULT_LIMIT`].
    pub fn from_path(path: &Path) -> Result<Scene, SceneError> {
        Scene::from_path_within(path, DEFAULT_LIMIT)
    }

    /// [`from_path`](Self::from_path) with a storage limit of `limit` bytes.
    pub fn from_path_within(path: &Path, limit: usize) -> Result<Scene, SceneError> {
        Scene::from_path_limited(
            path,
            Limits {
                storage: limit,
                ..Limits::default()
            },
        )
    }

    /// [`from_path`](Self::from_path) under `limits` (step storage and output size).
    pub fn from_path_limited(path: &Path, limits: Limits) -> Result<Scene, SceneError> {
        let origin = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| SceneError {
            origin: origin.clone(),
            location: None,
            message: format!("cannot read scene file: {e}"),
            too_large: None,
        })?;
        Scene::parse_bytes(&bytes, &origin, limits)
    }

    /// [`parse_limited`](Self::parse_limited) of raw bytes: text that is not UTF-8 is
    /// refused at the line of the first bad byte.
    pub fn parse_bytes(bytes: &[u8], origin: &str, limits: Limits) -> Result<Scene, SceneError> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let valid = std::str::from_utf8(&bytes[..e.valid_up_to()]).unwrap_or_default();
            SceneError {
                origin: origin.to_string(),
                location: Some(line_col(valid, valid.len())),
                message: "the file is not valid UTF-8 here (TOML files are UTF-8, comments too)"
                    .into(),
                too_large: None,
            }
        })?;
        Scene::parse_limited(text, origin, limits)
    }

    /// Parses scene text; `origin` names it in error messages (usually its path).
    /// Refuses a scene whose step storage would exceed [`DEFAULT_LIMIT`].
    pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
        Scene::parse_within(text, origin, DEFAULT_LIMIT)
    }

    /// [`parse`](Self::parse) with a storage limit of `limit` bytes, checked before any
    /// bead is generated or any pair is checked.
    pub fn parse_within(text: &str, origin: &str, limit: usize) -> Result<Scene, SceneError> {
        let limits = Limits {
            storage: limit,
            ..Limits::default()
        };
        Scene::parse_limited(text, origin, limits)
    }

    /// [`parse`](Self::parse) under `limits`, checked from the counts before any bead is
    /// generated or any pair is checked.
    pub fn parse_limited(text: &str, origin: &str, limits: Limits) -> Result<Scene, SceneError> {
        let toml_error = |e: toml::de::Error| {
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
                too_large: None,
            }
        };
        let doc = DeTable::parse(text).map_err(toml_error)?;
        let (mut scene, method_at) = resolve_document(doc, limits).map_err(|e| match e {
            Unresolved::Toml(e) => toml_error(e),
            Unresolved::Issue(i) => SceneError {
                origin: origin.to_string(),
                location: Some(i.span.map_or((1, 1), |s| line_col(text, s.start))),
                message: i.message,
                too_large: i.too_large,
            },
        })?;
        if let Some(b) = scene.periodic.as_mut() {
            b.method_line = method_at.map(|at| line_col(text, at).0);
        }
        Ok(scene)
    }

    /// The scene of a TOML document already parsed, and the offset of its `[box]`
    /// `method` in the text its spans refer to: [`parse_limited`](Self::parse_limited)
    /// after its parse, and what a sweep resolves for each point (its base parsed once,
    /// the point's values set in a copy of the document: no text written or read per
    /// point). `None` when the document is not a scene: the caller parses its text for
    /// the error, placed.
    pub(crate) fn from_document(
        doc: Spanned<DeTable<'_>>,
        limits: Limits,
    ) -> Option<(Scene, Option<usize>)> {
        resolve_document(doc, limits).ok()
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

    /// Species (type name) of each particle.
    pub fn species(&self) -> Vec<&str> {
        self.species.iter().map(|s| s.as_ref()).collect()
    }

    /// Types, radii, masses and bonds, for the trajectory files. Types are numbered
    /// in order of first appearance.
    pub fn topology(&self) -> Topology {
        let mut types: Vec<String> = Vec::new();
        // A scene edited in code may have fewer names than particles: the rest are "P".
        let typeid = (0..self.particles.len())
            .map(|k| {
                let s = self.species.get(k).map_or("P", |s| s.as_ref());
                types.iter().position(|t| t == s).unwrap_or_else(|| {
                    types.push(s.to_string());
                    types.len() - 1
                })
            })
            .collect();
        Topology {
            types,
            typeid,
            radius: self.radii(),
            mass: self
                .particles
                .iter()
                .map(|p| hydrorattle::particles::sphere_volume(p.radius) * p.density)
                .collect(),
            bonds: self.bonds.iter().map(|b| [b.i, b.j]).collect(),
            cell: self.periodic.map(|b| b.size),
        }
    }
}

/// Why a parsed document is not a scene, before it is placed in its text.
enum Unresolved {
    Toml(toml::de::Error),
    Issue(error::Issue),
}

/// A parsed document deserialized and resolved (the one way from a document to a
/// [`Scene`]); with the offset of its `[box]` `method`.
fn resolve_document(
    doc: Spanned<DeTable<'_>>,
    limits: Limits,
) -> Result<(Scene, Option<usize>), Unresolved> {
    let raw = RawScene::deserialize(toml::de::Deserializer::from(doc)).map_err(Unresolved::Toml)?;
    let method_at = raw.periodic.as_ref().and_then(|b| b.get_ref().method_at());
    let scene = raw.resolve(limits).map_err(Unresolved::Issue)?;
    Ok((scene, method_at))
}
