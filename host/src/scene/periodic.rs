//! A periodic box: the `[box]` table.
//!
//! ```toml
//! [box]
//! size = [20.0, 20.0, 20.0]   # Lx, Ly, Lz: every edge finite and > 0
//! method = "auto"             # "ewald" | "pse" | "auto" (default)
//! tolerance = 1e-6            # the fast path's relative error (1e-12 to 0.1)
//! ```
//!
//! The kernel's `Params::periodic`: the Ewald-summed RPY mobility (`docs/PERIODIC.md`),
//! bonds, springs and contacts through the minimum image, positions kept unwrapped
//! (the trajectories give the box: `docs/SCENES.md`). `"ewald"` is the exact
//! reference path, summed to about the precision's epsilon whatever the tolerance;
//! `"pse"` is the positively split Ewald fast path (`O(N log N)` products, the kernel's
//! `Params::pse` at `tolerance`), which gives products only: a run with it is
//! matrix-free (written back as `matrix_free = true`), and a scene whose method,
//! solver or noise needs the assembled mobility refuses it at its line
//! ([`PseUnsupported`]); `"auto"` resolves by [`BoxMethod::resolve`] and the run's
//! `scene.toml` names the method it picked. Refused at the value at fault: an edge not finite or not
//! positive, a tolerance outside PSE's `[1e-12, 0.1]`, a sphere whose radius is not below half the
//! smallest edge (it would overlap its own image), a box with a `[wall]` (the wall's
//! image system is free space's), and (by the kernel's own check of the first step) a
//! bond not shorter than half the smallest edge and the Oseen level. Rotation is
//! accepted: the kernel sums the box's `rt` and `rr` blocks too.

use std::fmt;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::Particle;
use super::error::{Issue, issue};
use super::raw::{Bound, S, number};
use super::resolve::BodySpans;

/// How the box's mobility is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum BoxMethod {
    /// The exact Ewald sum (`mobility::periodic`), `O(N^2)` per product.
    Ewald,
    /// The positively split Ewald fast path, `O(N log N)` per product, to `tolerance`.
    Pse,
    /// Chosen by [`BoxMethod::resolve`].
    #[default]
    Auto,
}

impl BoxMethod {
    /// The method a run uses: `"auto"` is `"pse"` where the scene needs mobility
    /// products only and PSE is the cheaper path there (`pse_pays`: the measured cost
    /// model of [`super::box_cost`], in the sphere count, the box and the tolerance),
    /// `"ewald"` otherwise. A dilute box is Ewald's: a lone sphere in a box of 50 costs
    /// PSE a grid of 80^3 points (0.15 s a product against 5e-5 s). `"ewald"` and
    /// `"pse"` are themselves.
    pub fn resolve(self, pse_pays: bool) -> BoxMethod {
        match self {
            BoxMethod::Auto if pse_pays => BoxMethod::Pse,
            BoxMethod::Auto => BoxMethod::Ewald,
            m => m,
        }
    }
}

/// The default `tolerance`: the fast path's relative error.
pub const DEFAULT_BOX_TOLERANCE: f64 = 1e-6;

/// A rectangular periodic box.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PeriodicBox {
    /// Edges `Lx, Ly, Lz` (finite, > 0).
    pub size: [f64; 3],
    /// How its mobility is computed.
    pub method: BoxMethod,
    /// The fast path's relative error, `1e-12 <= tolerance <= 0.1` (the Ewald path sums to
    /// about the precision's epsilon whatever it says).
    pub tolerance: f64,
    /// Line of the `method` key in the scene file that set it (to place a run's
    /// refusal of `"pse"`); not part of the box (ignored by `==`, not written).
    #[serde(skip)]
    pub method_line: Option<usize>,
}

impl PartialEq for PeriodicBox {
    fn eq(&self, o: &Self) -> bool {
        (self.size, self.method, self.tolerance) == (o.size, o.method, o.tolerance)
    }
}

impl PeriodicBox {
    /// The box's smallest edge.
    pub fn min_edge(&self) -> f64 {
        self.size.iter().fold(f64::INFINITY, |m, &l| m.min(l))
    }

    /// The kernel's box (`hydrorattle::Periodic`) in f64, whose minimum image is the
    /// one the steps take; `None` for an edge not finite or not positive.
    pub fn kernel(&self) -> Option<hydrorattle::Periodic<f64>> {
        hydrorattle::Periodic::new(self.size).ok()
    }
}

/// `[box]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBox {
    size: S<[f64; 3]>,
    method: Option<Spanned<BoxMethod>>,
    tolerance: S<f64>,
}

impl RawBox {
    /// Span of `size`, when given.
    pub(super) fn size_span(&self) -> Option<std::ops::Range<usize>> {
        self.size.as_ref().map(|s| s.span())
    }

    /// Where `method` starts, when given (the parser turns it into
    /// [`PeriodicBox::method_line`]).
    pub(super) fn method_at(&self) -> Option<usize> {
        self.method.as_ref().map(|m| m.span().start)
    }

    /// The method as written (`"auto"` when left out).
    pub(super) fn method(&self) -> BoxMethod {
        self.method
            .as_ref()
            .map_or(BoxMethod::Auto, |m| *m.get_ref())
    }

    /// Span of `method`, else of `tolerance`, else of `size`, when given.
    pub(super) fn method_span(&self) -> Option<std::ops::Range<usize>> {
        let method = self.method.as_ref().map(|m| m.span());
        method
            .or_else(|| self.tolerance_span())
            .or_else(|| self.size_span())
    }

    /// Span of `tolerance`, when given.
    pub(super) fn tolerance_span(&self) -> Option<std::ops::Range<usize>> {
        self.tolerance.as_ref().map(|t| t.span())
    }
}

/// Resolves `[box]`; `size` is the suspension generator's edge when the scene has one
/// (then the table must not give its own), required otherwise. The parser sets
/// `method_line` (it holds the text).
pub(super) fn resolve(
    raw: &Spanned<RawBox>,
    generated: Option<[f64; 3]>,
) -> Result<PeriodicBox, Issue> {
    let r = raw.get_ref();
    let size = match (&r.size, generated) {
        (Some(s), Some(_)) => {
            return Err(issue(
                s.span(),
                "[suspension] sets the box from its count and fraction: leave [box] size out",
            ));
        }
        (None, Some(g)) => g,
        (None, None) => {
            return Err(issue(
                raw.span(),
                "missing field `size` in [box] (the edges [Lx, Ly, Lz])",
            ));
        }
        (Some(s), None) => {
            let v = *s.get_ref();
            if let Some(k) = v.iter().position(|l| !(l.is_finite() && *l > 0.0)) {
                let axis = ["x", "y", "z"][k];
                return Err(issue(
                    s.span(),
                    format!(
                        "box size: every edge must be finite and > 0, not L{axis} = {}",
                        crate::output::format_f64(v[k])
                    ),
                ));
            }
            v
        }
    };
    let tolerance = number(
        &r.tolerance,
        DEFAULT_BOX_TOLERANCE,
        "box tolerance",
        Bound::Positive,
    )?;
    // PSE's range, the kernel's (`Pse::with_xi`), refused here at the key rather than
    // by the first step (for "ewald" too: the key is PSE's, and "auto" may pick it).
    use hydrorattle::mobility::pse::{MAX_TOLERANCE, MIN_TOLERANCE};
    if let Some(t) = r
        .tolerance
        .as_ref()
        .filter(|_| !(MIN_TOLERANCE..=MAX_TOLERANCE).contains(&tolerance))
    {
        return Err(issue(
            t.span(),
            format!(
                "box tolerance must be between {MIN_TOLERANCE:e} and {MAX_TOLERANCE} (PSE's relative error), not {}",
                crate::output::format_f64(tolerance)
            ),
        ));
    }
    let method = r.method();
    Ok(PeriodicBox {
        size,
        method,
        tolerance,
        method_line: None,
    })
}

/// Refuses a sphere that would overlap its own image: radius not below half the
/// smallest edge, placed at the sphere.
pub(super) fn check_particles(
    b: &PeriodicBox,
    particles: &[Particle],
    spans: &BodySpans,
) -> Result<(), Issue> {
    let half = 0.5 * b.min_edge();
    match particles
        .iter()
        .position(|p| p.radius >= half || p.radius.is_nan())
    {
        None => Ok(()),
        Some(k) => Err(issue(
            spans.position(k),
            format!(
                "particle {k} has radius {}, not below half the box's smallest edge ({half}): it would overlap its own image",
                particles[k].radius
            ),
        )),
    }
}

/// A box and a wall together, placed at the box.
pub(super) fn refuse_wall(raw: &Spanned<RawBox>) -> Issue {
    issue(
        raw.get_ref().size_span().unwrap_or(raw.span()),
        "a periodic [box] with a [wall] is not supported (the wall's mobility is that of a wall in unbounded fluid; a wall-bounded periodic layer needs another Green's function)",
    )
}

/// A run of a scene whose `[box]` asks for `method = "pse"` with a method, solver or
/// noise that needs the assembled mobility (PSE gives products only).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PseUnsupported {
    /// The scene file, when the run came from one.
    pub origin: Option<String>,
    /// The line of `method = "pse"`, when the scene was read from a file.
    pub line: Option<usize>,
    /// What needs the assembled mobility.
    pub why: &'static str,
}

impl fmt::Display for PseUnsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.origin, self.line) {
            (Some(o), Some(l)) => write!(f, "{o}:{l}: ")?,
            (None, Some(l)) => write!(f, "line {l}: ")?,
            (Some(o), None) => write!(f, "{o}: ")?,
            (None, None) => {}
        }
        write!(
            f,
            "[box] method = \"pse\" gives mobility products only, and {} needs the assembled mobility; use method = \"ewald\" or \"auto\"",
            self.why
        )
    }
}

impl std::error::Error for PseUnsupported {}

/// Whether PSE's parameters for a box of edges `size`, spheres up to radius `a_max` and
/// `tolerance` are within the kernel's bounds (`mobility::pse::Pse::new`: a grid edge
/// of at most `MAX_GRID`, a support of at most `MAX_SUPPORT`, the tolerance's range):
/// `"auto"` picks PSE only then ([`BoxMethod::resolve`] with it and "products only"),
/// so that a resolved scene written back runs (a dilute suspension's box can need a
/// grid past the bounds; the Ewald path has none). The rule of scenes and of the Python
/// package's `mobility_dot`.
pub fn pse_fits(size: [f64; 3], a_max: f64, tolerance: f64) -> bool {
    hydrorattle::Periodic::new(size)
        .is_ok_and(|cell| hydrorattle::mobility::pse::Pse::new(cell, a_max, tolerance).is_ok())
}

/// What in a scene of this model, integrator and noise needs the assembled mobility
/// (so PSE cannot run it), or `None` where mobility products suffice: the overdamped
/// or springs method (matrix-free), `level = "manual"` (the automatic level may pick
/// another method), no rotation, the `"auto"` or `"krylov"` solver (Sweep and Newton
/// read single blocks), no Cholesky noise and no near field (`near`: the Stokesian
/// dynamics mobility is formed from the assembled far-field blocks). Known before the
/// body is generated, so that a scene is sized for the path it will run.
pub fn needs_matrix(
    model: &super::Model,
    i: &super::Integrator,
    brownian: Option<super::Thermal>,
    near: bool,
) -> Option<&'static str> {
    use super::{Level, Method, Solver, Sqrt};
    if near {
        return Some("[near_field]");
    }
    if !matches!(
        i.method,
        Method::Overdamped | Method::Overdamped2 | Method::Springs
    ) {
        return Some("a method other than overdamped, overdamped2 or springs");
    }
    if model.level != Level::Manual {
        return Some("level = \"auto\" (it may pick another method)");
    }
    if model.rotation {
        return Some("rotation");
    }
    if matches!(i.solver, Solver::Sweep | Solver::Newton) {
        return Some("the sweep or newton solver");
    }
    let thermal = brownian.is_some_and(|b| b.temperature > 0.0);
    if thermal && brownian.is_some_and(|b| b.sqrt == Sqrt::Cholesky) {
        return Some("[brownian] sqrt = \"cholesky\"");
    }
    None
}

impl super::Scene {
    /// What in this scene needs the assembled mobility (so PSE cannot run it), or
    /// `None` where mobility products suffice (the rule reads the model, the
    /// integrator and the noise only, so the parser applies it before the body).
    pub fn needs_matrix(&self) -> Option<&'static str> {
        needs_matrix(
            &self.model,
            &self.integrator,
            self.brownian,
            self.near_field.is_some(),
        )
    }

    /// Whether this scene needs mobility products only ([`needs_matrix`](Self::needs_matrix)).
    pub fn products_only(&self) -> bool {
        self.needs_matrix().is_none()
    }

    /// This scene with its box method resolved for the run ([`BoxMethod::resolve`]:
    /// `"auto"` becomes the method it picks, so the run's `scene.toml` re-runs the
    /// same path); a run on PSE is matrix-free (`matrix_free = true`, written back).
    pub fn with_box_resolved(mut self) -> super::Scene {
        let only = self.products_only();
        let pays = only && self.pse_pays();
        if let Some(b) = self.periodic.as_mut() {
            b.method = b.method.resolve(pays);
            if b.method == BoxMethod::Pse && only {
                self.integrator.matrix_free = true;
            }
        }
        self
    }

    /// Whether PSE runs this box, its largest radius and its tolerance, and costs less
    /// than the Ewald sum for its spheres ([`super::box_cost::pse_pays`]).
    fn pse_pays(&self) -> bool {
        let Some(b) = self.periodic else {
            return true;
        };
        let radii = self.radii();
        let a_max = radii.iter().fold(0.0, |m: f64, &a| m.max(a));
        let cost = super::box_cost::BoxCost::of(b.size, radii.len(), a_max, b.tolerance);
        let thermal = self.brownian.is_some_and(|t| t.temperature > 0.0);
        let constraints = !self.bonds.is_empty()
            || !self.pinned.is_empty()
            || self
                .contact
                .is_some_and(|c| c.hard_capacity(radii.len()).is_some());
        let midpoint = self
            .brownian
            .is_some_and(|t| t.drift == super::Drift::Midpoint);
        let work = super::box_cost::Work {
            constraints,
            thermal,
            midpoint: thermal && midpoint && constraints,
            matrix_free: self.integrator.matrix_free,
        };
        cost.per_step(work).pse_pays()
    }

    /// Refuses a run of a box whose method is `"pse"` where the scene needs the
    /// assembled mobility ([`PseUnsupported`], placed at its line in `origin`).
    pub fn check_box_runs(&self, origin: Option<&str>) -> Result<(), PseUnsupported> {
        match (self.periodic, self.needs_matrix()) {
            (Some(b), Some(why)) if b.method == BoxMethod::Pse => Err(PseUnsupported {
                origin: origin.map(str::to_string),
                line: b.method_line,
                why,
            }),
            _ => Ok(()),
        }
    }
}
