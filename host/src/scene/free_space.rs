//! Free space's product: the `[free_space]` table.
//!
//! ```toml
//! [free_space]
//! method = "fast"     # "dense" (default) | "fast" | "auto"
//! tolerance = 1e-4    # the fast product's relative error (1e-10 to 0.1)
//! reweigh = true      # weigh the fast product against the pair sums before each step
//! ```
//!
//! The table names how the mobility of spheres in open fluid is applied, as `[box]`
//! names the box's. `"dense"` is every path that existed before it (the stored
//! mobility, or its pair sums with `matrix_free`: `O(N^2)`, exact to rounding).
//! `"fast"` is the kernel's fast free-space RPY product (`mobility::free_fast`,
//! `O(N log N)`, `docs/FREE.md`; the kernel's `Params::pse` at `tolerance` with no box
//! and no wall): it gives products only, so the run is matrix-free (written back as
//! `matrix_free = true`) and the constraints are solved by Krylov. A scene that needs
//! what it does not give is refused at `method`: a `[wall]` or a `[box]` (their
//! products are their own), another level than RPY, a
//! method or level that stores the mobility (`matrix_free`'s rule), the Cholesky
//! factor of the noise. With a `[near_field]` the fast product is the far field of the
//! near field's iterative product (`docs/NEAR.md`, "On the fast free-space product"). The storage is sized without the mobility (`O(N)`, no `N^2`
//! term), so a cloud of 10^5 spheres is not refused as dense. `"auto"` picks, when the
//! run starts, the path a measured cost model says is fastest among those that fit the
//! storage limit (`scene::free_cost`: the stored mobility, its compact copy,
//! matrix-free or fast); where `"fast"` cannot run the scene it is `"dense"` at once.
//! An `"auto"` scene is sized at read time as the fast path would be (the choice then
//! checks each path's storage before taking it).
//!
//! `reweigh` (default `true` under `"auto"`, `false` under `"fast"`): a run on the fast
//! product weighs it again before every step against the pair sums, on the pairs
//! counted within its cutoff (`scene::free_reweigh`), and takes the cheaper. A cloud
//! that leaves a tail stretches the box the fast product is sized from and makes its
//! near part dearer as the run goes on, while the pair sums cost the same whatever the
//! shape. The written scene keeps the key, so that a resumed run weighs as the
//! uninterrupted one did.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::error::{Issue, issue};
use super::raw::{Bound, S, number};
use super::{Hydrodynamics, Integrator, Level, Method, Model, Precision, Sqrt, Thermal};

/// How the free-space mobility is applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FreeMethod {
    /// The stored mobility or its pair sums, `O(N^2)`, exact to rounding.
    #[default]
    Dense,
    /// The fast free-space product, `O(N log N)`, to `tolerance`.
    Fast,
    /// Chosen when the run starts by the measured cost model
    /// ([`Scene::with_free_resolved`](super::Scene::with_free_resolved)).
    Auto,
}

/// The default `tolerance` of `"fast"`: the product's measured error is 5 to 55 times
/// below the tolerance asked (`docs/FREE.md`), so `1e-4` gives about the box's default
/// accuracy (`1e-6`) at a third of the cost of asking `1e-6`.
pub const DEFAULT_FREE_TOLERANCE: f64 = 1e-4;

/// The `[free_space]` table, resolved.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FreeSpace {
    /// How the mobility is applied.
    pub method: FreeMethod,
    /// The fast product's relative error (`"dense"` ignores it).
    pub tolerance: f64,
    /// Whether a run on the fast product weighs it against the pair sums before each
    /// step (`scene::free_reweigh`); only with `"fast"` or `"auto"`.
    pub reweigh: bool,
}

impl FreeSpace {
    /// Whether the run may take the fast product (`"fast"`, or `"auto"` not yet
    /// resolved): the scene is then sized without the `N^2` mobility.
    pub fn may_be_fast(&self) -> bool {
        matches!(self.method, FreeMethod::Fast | FreeMethod::Auto)
    }

    /// Whether the run weighs the fast product against the pair sums before each step:
    /// `reweigh` on `"fast"` (`"auto"` resolved to it).
    pub fn reweighs(&self) -> bool {
        self.reweigh && self.method == FreeMethod::Fast
    }

    /// The kernel's `Params::pse` for this table: the tolerance when `"fast"`.
    pub fn fast_tolerance(&self) -> Option<f64> {
        (self.method == FreeMethod::Fast).then_some(self.tolerance)
    }
}

/// `[free_space]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFreeSpace {
    method: Option<Spanned<FreeMethod>>,
    tolerance: S<f64>,
    reweigh: S<bool>,
}

/// What the rest of the scene says that `"fast"` must agree with.
pub(super) struct Context<'a> {
    pub(super) model: &'a Model,
    pub(super) integrator: &'a Integrator,
    pub(super) brownian: Option<Thermal>,
    /// Spans of the `[wall]` and `[box]` tables, when given.
    pub(super) wall: Option<std::ops::Range<usize>>,
    pub(super) periodic: Option<std::ops::Range<usize>>,
}

/// Resolves `[free_space]`, refusing at `method` what `"fast"` cannot run.
pub(super) fn resolve(raw: &Spanned<RawFreeSpace>, cx: &Context<'_>) -> Result<FreeSpace, Issue> {
    let r = raw.get_ref();
    if cx.periodic.is_some() {
        return Err(issue(
            raw.span(),
            "[free_space] names free space's product: a [box] names its own (`[box] method`)",
        ));
    }
    let tolerance = number(
        &r.tolerance,
        DEFAULT_FREE_TOLERANCE,
        "free_space tolerance",
        Bound::Positive,
    )?;
    use hydrorattle::mobility::free_fast::{MAX_TOLERANCE, MIN_TOLERANCE, min_tolerance};
    let floor = match cx.integrator.precision {
        Precision::F32 => min_tolerance::<f32>(),
        Precision::F64 => MIN_TOLERANCE,
    };
    if let Some(t) = r.tolerance.as_ref()
        && !(floor..=MAX_TOLERANCE).contains(&tolerance)
    {
        return Err(issue(
            t.span(),
            format!(
                "free_space tolerance must be between {floor:e} and {MAX_TOLERANCE} in this precision, not {tolerance}"
            ),
        ));
    }
    let method = r
        .method
        .as_ref()
        .map_or(FreeMethod::Dense, |m| *m.get_ref());
    if let (FreeMethod::Fast, Some(at)) = (method, r.method.as_ref().map(|m| m.span()))
        && let Some(why) = unsupported(cx)
    {
        return Err(issue(at, format!("method = \"fast\" {why}")));
    }
    let reweigh = match (&r.reweigh, method) {
        (Some(w), FreeMethod::Dense) if *w.get_ref() => {
            return Err(issue(
                w.span(),
                "reweigh weighs the fast product against the pair sums before each step: it needs method = \"fast\" or \"auto\"",
            ));
        }
        (Some(w), _) => *w.get_ref(),
        (None, m) => m == FreeMethod::Auto,
    };
    // "auto" where the fast product cannot run: the dense paths, resolved at once.
    let method = match method {
        FreeMethod::Auto if unsupported(cx).is_some() => FreeMethod::Dense,
        m => m,
    };
    Ok(FreeSpace {
        method,
        tolerance,
        reweigh: reweigh && method != FreeMethod::Dense,
    })
}

/// Why `"fast"` cannot run this scene, if it cannot.
fn unsupported(cx: &Context<'_>) -> Option<&'static str> {
    let m = cx.model;
    let i = cx.integrator;
    let cholesky = cx
        .brownian
        .is_some_and(|b| b.temperature > 0.0 && b.sqrt == Sqrt::Cholesky);
    Some(match () {
        _ if cx.wall.is_some() => {
            "is the free-space product: above a [wall] or in a [slit] the mobility is the walls' (use \"dense\")"
        }
        _ if m.hydrodynamics != Hydrodynamics::Rpy => {
            "gives the RPY product only: hydrodynamics = \"rpy\""
        }
        _ if !matches!(
            i.method,
            Method::Overdamped | Method::Overdamped2 | Method::Springs
        ) || m.level != Level::Manual =>
        {
            "gives products only: it needs method = \"overdamped\", \"overdamped2\" or \"springs\" and level = \"manual\" \
             (the other methods store or factorise the mobility)"
        }
        _ if cholesky => {
            "gives products only: [brownian] sqrt = \"cholesky\" needs the stored mobility (use \"auto\" or \"lanczos\")"
        }
        _ => return None,
    })
}
