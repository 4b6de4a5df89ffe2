//! The scene's body: a `[suspension]` (and the `[floor]` under it), a `[helix]`, or
//! explicit `[[particle]]` and `[[bond]]` tables, one of them; each sized from its
//! counts against the budgets (`budget.rs`) before it is generated, so an oversized
//! body never reaches the allocator. Apart from the rest of the resolution because it
//! is the part that chooses among the tables and makes the spheres; the spans it
//! keeps ([`BodySpans`]) place every later geometric error.

use std::borrow::Cow;
use std::ops::Range;

use super::budget::{check_counts, check_output, fits};
use super::integrator::resolve_integrator;
use crate::scene::bodies::{ParticleSpans, resolve_bonds, resolve_helix, resolve_particles};
use crate::scene::error::{Issue, issue, too_large};
use crate::scene::raw::RawScene;
use crate::scene::{Bond, Floor, Helix, Integrator, Particle, Suspension};
use crate::sizing::{Limits, Plan};

/// What [`RawScene::body`] resolves, for the [`Scene`](crate::scene::Scene) and its
/// later checks (read field by field where the scene is made).
pub(super) struct Body {
    /// Every sphere (generated, or from the tables).
    pub(super) particles: Vec<Particle>,
    /// Every bond, lengths resolved.
    pub(super) bonds: Vec<Bond>,
    /// The helix generator's settings, when the body is a helix.
    pub(super) helix: Option<Helix>,
    /// Where the body's values are, to place geometric errors.
    pub(super) spans: BodySpans,
    /// Each sphere's species.
    pub(super) species: Vec<Cow<'static, str>>,
    /// The suspension's settings and its box's size, when the body is a suspension.
    pub(super) suspension: Option<(Suspension, [f64; 3])>,
    /// The cloud's settings, when the body is a cloud.
    pub(super) cloud: Option<crate::scene::Cloud>,
    /// The floor laid under the suspension, if any.
    pub(super) floor: Option<Floor>,
    /// The pinned spheres (ascending).
    pub(super) pinned: Vec<usize>,
}

impl RawScene {
    /// The body, sized against `plans` and `limits` before it is generated; output
    /// errors of explicit particles and the helix are placed at `output_span`.
    pub(super) fn body(
        &self,
        plans: &[Plan],
        limits: Limits,
        integrator: &Integrator,
        every: usize,
        output_span: Range<usize>,
    ) -> Result<Body, Issue> {
        let limit = limits.storage;
        let (mut suspension, mut cloud) = (None, None);
        let (mut floor, mut pinned) = (None, Vec::new());
        if let (Some(f), None) = (&self.floor, &self.suspension) {
            return Err(issue(
                f.span(),
                "a [floor] lays a pinned layer under a [suspension]: give one (or pin [[particle]] tables with `fixed = true`)",
            ));
        }
        let (particles, bonds, helix, body_span, species) = match (&self.helix, &self.particles) {
            _ if self.cloud.is_some() => {
                let (c, particles) = self.generate_cloud(plans, limits, every)?;
                cloud = Some(c);
                let species = vec![Cow::Borrowed("sphere"); particles.len()];
                let spans = BodySpans::Helix(self.cloud.as_ref().map_or(0..0, |c| c.span()));
                (particles, Vec::new(), None, spans, species)
            }
            _ if self.suspension.is_some() => {
                let (s, (mut particles, edge)) = self.generate_suspension(plans, limits, every)?;
                let mut size = [edge; 3];
                let mut species = vec![Cow::Borrowed("sphere"); particles.len()];
                if let Some(raw) = &self.floor {
                    let f = crate::scene::floor::resolve(raw, s.radius, s.density)?;
                    let at = crate::scene::floor::radius_span(raw);
                    // Sized before it is laid, like the suspension: a small floor
                    // radius asks for k^2 spheres, which must not reach the allocator.
                    let k = f.count(edge);
                    let n = k.saturating_add(particles.len());
                    fits(plans, n, 0, limits.storage).map_err(|e| too_large(at.clone(), e))?;
                    check_output(integrator, every, n, limits.output)
                        .map_err(|m| issue(at.clone(), m))?;
                    (particles, size) = f.lay(&particles, edge).map_err(|m| issue(at, m))?;
                    pinned = (0..k).collect();
                    species.splice(0..0, vec![Cow::Borrowed("floor"); k]);
                    floor = Some(f);
                }
                suspension = Some((s, size));
                let spans = BodySpans::Helix(self.suspension.as_ref().map_or(0..0, |s| s.span()));
                (particles, Vec::new(), None, spans, species)
            }
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
                // Sized from the count alone: a helix too large to run is never generated.
                let at = h.get_ref().tails.as_ref().map_or(h.span(), |t| t.span());
                fits(plans, helix.tails.saturating_add(1), helix.tails, limit)
                    .map_err(|e| too_large(at, e))?;
                check_output(integrator, every, helix.tails + 1, limits.output)
                    .map_err(|m| issue(output_span.clone(), m))?;
                let chain = helix.generate().map_err(|m| issue(h.span(), m))?;
                let (particles, bonds) = (chain.particles(), chain.scene_bonds());
                let species = (0..=helix.tails)
                    .map(|k| Cow::Borrowed(if k == 0 { "head" } else { "tail" }))
                    .collect();
                let spans = BodySpans::Helix(h.span());
                (particles, bonds, Some(helix), spans, species)
            }
            (None, Some(ps)) => {
                let raw_bonds = self.bonds.as_ref().map_or(&[][..], |b| b.get_ref());
                check_counts(plans, ps.get_ref(), raw_bonds, limit)?;
                check_output(integrator, every, ps.get_ref().len(), limits.output)
                    .map_err(|m| issue(output_span.clone(), m))?;
                let (particles, spans, species) = resolve_particles(ps)?;
                pinned = (ps.get_ref().iter().enumerate())
                    .filter(|(_, p)| p.fixed.as_ref().is_some_and(|f| *f.get_ref()))
                    .map(|(k, _)| k)
                    .collect();
                let species = species.into_iter().map(Cow::Owned).collect();
                let (bonds, bond_spans) =
                    resolve_bonds(self.bonds.as_ref(), &particles, integrator)?;
                let spans = BodySpans::Particles(spans, bond_spans);
                (particles, bonds, None, spans, species)
            }
            (None, None) => {
                return Err(Issue::unplaced(
                    "the scene has no particles: give [[particle]] tables or a [helix] table",
                ));
            }
        };
        Ok(Body {
            particles,
            bonds,
            helix,
            spans: body_span,
            species,
            suspension,
            cloud,
            floor,
            pinned,
        })
    }

    /// The `[suspension]` table's spheres and box edge (the only body: no helix, no
    /// explicit particles or bonds), sized from its count before anything is placed.
    fn generate_suspension(
        &self,
        plans: &[Plan],
        limits: Limits,
        every: usize,
    ) -> Result<(Suspension, (Vec<Particle>, f64)), Issue> {
        let Some(raw) = &self.suspension else {
            return Err(Issue::unplaced("no [suspension] table"));
        };
        let other = [
            self.helix.as_ref().map(|h| h.span()),
            self.particles.as_ref().map(|p| p.span()),
            self.bonds.as_ref().map(|b| b.span()),
        ];
        if let Some(at) = other.into_iter().flatten().next() {
            return Err(issue(
                at,
                "a [suspension] makes its own spheres (and no bonds): leave out [helix], [[particle]] and [[bond]]",
            ));
        }
        let s = crate::scene::suspension::resolve(raw)?;
        let at = raw.get_ref().count_span().unwrap_or(raw.span());
        self.check_generated(plans, limits, every, s.count, at)?;
        let body = s.generate().map_err(|m| issue(raw.span(), m))?;
        Ok((s, body))
    }
}

impl RawScene {
    /// The `[cloud]` table's spheres (the only body: no suspension, helix, explicit
    /// particles or bonds), sized from its count before anything is placed.
    fn generate_cloud(
        &self,
        plans: &[Plan],
        limits: Limits,
        every: usize,
    ) -> Result<(crate::scene::Cloud, Vec<Particle>), Issue> {
        let Some(raw) = &self.cloud else {
            return Err(Issue::unplaced("no [cloud] table"));
        };
        let other = [
            self.suspension.as_ref().map(|s| s.span()),
            self.helix.as_ref().map(|h| h.span()),
            self.particles.as_ref().map(|p| p.span()),
            self.bonds.as_ref().map(|b| b.span()),
        ];
        if let Some(at) = other.into_iter().flatten().next() {
            return Err(issue(
                at,
                "a [cloud] makes its own spheres (and no bonds): leave out [suspension], [helix], [[particle]] and [[bond]]",
            ));
        }
        let c = crate::scene::cloud::resolve(raw)?;
        let at = raw.get_ref().count_span().unwrap_or(raw.span());
        self.check_generated(plans, limits, every, c.count, at)?;
        let particles = c.generate().map_err(|m| issue(raw.span(), m))?;
        Ok((c, particles))
    }

    /// A generated body of `count` spheres (no bonds) checked against the storage and
    /// output limits before any sphere is placed, refused at `at` (its `count`).
    fn check_generated(
        &self,
        plans: &[Plan],
        limits: Limits,
        every: usize,
        count: usize,
        at: Range<usize>,
    ) -> Result<(), Issue> {
        fits(plans, count, 0, limits.storage).map_err(|e| too_large(at.clone(), e))?;
        if let Some(i) = self.integrator.as_ref().map(|i| i.get_ref()) {
            let i = resolve_integrator(i)?;
            check_output(&i, every, count, limits.output).map_err(|m| issue(at, m))?;
        }
        Ok(())
    }
}

/// Spans of the body's values, to place geometric errors.
pub(in crate::scene) enum BodySpans {
    /// A generated body (the helix's or the suspension's table).
    Helix(Range<usize>),
    /// Per particle: span of its position, span of its density (or of its position);
    /// per bond: span of its length (or of its `between`).
    Particles(ParticleSpans, Vec<Range<usize>>),
}

impl BodySpans {
    pub(in crate::scene) fn position(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v, _) => v[k].0.clone(),
        }
    }

    pub(in crate::scene) fn density(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v, _) => v[k].1.clone(),
        }
    }

    pub(in crate::scene) fn bond(&self, l: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(_, b) => b[l].clone(),
        }
    }
}
