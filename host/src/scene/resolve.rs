//! From the raw form to a [`Scene`]: defaults filled in, numbers and geometry checked,
//! the helix generated, each error placed at the value at fault. The storage a scene
//! needs is checked from its counts before anything is generated or pair-checked.

use std::borrow::Cow;
use std::ops::Range;

use super::bodies::{
    ParticleSpans, check_geometry, resolve_bonds, resolve_helix, resolve_particles,
};
use super::error::{Issue, issue, too_large};
use super::raw::{Bound, RawBond, RawIntegrator, RawParticle, RawScene, number, vector};
use super::{
    Flow, Fluid, Integrator, Level, Method, Model, Output, Precision, Scene, Sqrt, TARGET_FRAMES,
};
use crate::sizing::{Limits, Plan, TooLarge};

impl RawScene {
    /// The scene, refused when its step storage or its output would exceed `limits`.
    pub(super) fn resolve(self, limits: Limits) -> Result<Scene, Issue> {
        let limit = limits.storage;
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
        let contact = self
            .contact
            .as_ref()
            .map(super::contact::resolve)
            .transpose()?;
        let Some(raw_int) = &self.integrator else {
            return Err(Issue::unplaced(
                "missing table [integrator] (method, dt and duration are required)",
            ));
        };
        let integrator = resolve_integrator(raw_int.get_ref())?;
        check_turn(&self, &flow, integrator.dt)?;
        if let Some(m) = raw_int
            .get_ref()
            .matrix_free
            .as_ref()
            .filter(|m| *m.get_ref())
        {
            let runs = matches!(integrator.method, Method::Overdamped | Method::Springs);
            if !runs || model.level != Level::Manual {
                return Err(issue(
                    m.span(),
                    "matrix_free needs method = \"overdamped\" or \"springs\" and level = \"manual\" \
                     (the other methods store or factorise the mobility)",
                ));
            }
        }
        let brownian = match &self.brownian {
            None => None,
            Some(b) => Some(b.resolve(&model, &integrator)?),
        };
        let cholesky = brownian.is_some_and(|b| b.temperature > 0.0 && b.sqrt == Sqrt::Cholesky);
        if let Some(m) = raw_int.get_ref().matrix_free.as_ref()
            && *m.get_ref()
            && cholesky
        {
            return Err(issue(
                m.span(),
                "matrix_free draws the noise by Lanczos: [brownian] sqrt = \"cholesky\" \
                     needs the stored mobility (use \"auto\" or \"lanczos\")",
            ));
        }
        if let (Some(c), Some(raw)) = (contact, &self.contact) {
            super::contact::check_method(c, raw, &integrator, brownian.as_ref())?;
        }
        let wall = match &self.wall {
            None => None,
            Some(raw) => {
                let w = super::wall::resolve(raw)?;
                super::wall::check_method(raw, &model, &integrator)?;
                Some(w)
            }
        };
        if let (Some(b), Some(_)) = (&self.periodic, &self.wall) {
            return Err(super::periodic::refuse_wall(b));
        }
        let every = match self.output.as_ref().and_then(|o| o.every.as_ref()) {
            None => integrator.steps().div_ceil(TARGET_FRAMES).max(1),
            Some(e) if *e.get_ref() == 0 => {
                return Err(issue(e.span(), "every must be >= 1 (steps between frames)"));
            }
            // Past the last step `every` changes nothing: held at the step count, it
            // stays a number a scene file can hold.
            Some(e) => (*e.get_ref()).min(integrator.steps()),
        };
        let plans = plans(
            &model,
            &integrator,
            &flow,
            contact,
            brownian,
            wall.is_some(),
        );
        let every_span = self
            .output
            .as_ref()
            .and_then(|o| o.every.as_ref())
            .map(|e| e.span());
        let output_span = every_span.unwrap_or_else(|| raw_int.get_ref().duration.span());

        let mut suspension = None;
        let (mut floor, mut pinned) = (None, Vec::new());
        if let (Some(f), None) = (&self.floor, &self.suspension) {
            return Err(issue(
                f.span(),
                "a [floor] lays a pinned layer under a [suspension]: give one (or pin [[particle]] tables with `fixed = true`)",
            ));
        }
        let (particles, bonds, helix, body_span, species) = match (&self.helix, &self.particles) {
            _ if self.suspension.is_some() => {
                let (s, (mut particles, edge)) = self.generate_suspension(&plans, limits, every)?;
                let mut size = [edge; 3];
                let mut species = vec![Cow::Borrowed("sphere"); particles.len()];
                if let Some(raw) = &self.floor {
                    let f = super::floor::resolve(raw, s.radius, s.density)?;
                    let at = super::floor::radius_span(raw);
                    // Sized before it is laid, like the suspension: a small floor
                    // radius asks for k^2 spheres, which must not reach the allocator.
                    let k = f.count(edge);
                    let n = k.saturating_add(particles.len());
                    fits(&plans, n, 0, limits.storage).map_err(|e| too_large(at.clone(), e))?;
                    check_output(&integrator, every, n, limits.output)
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
                fits(&plans, helix.tails.saturating_add(1), helix.tails, limit)
                    .map_err(|e| too_large(at, e))?;
                check_output(&integrator, every, helix.tails + 1, limits.output)
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
                check_counts(&plans, ps.get_ref(), raw_bonds, limit)?;
                check_output(&integrator, every, ps.get_ref().len(), limits.output)
                    .map_err(|m| issue(output_span.clone(), m))?;
                let (particles, spans, species) = resolve_particles(ps)?;
                pinned = (ps.get_ref().iter().enumerate())
                    .filter(|(_, p)| p.fixed.as_ref().is_some_and(|f| *f.get_ref()))
                    .map(|(k, _)| k)
                    .collect();
                let species = species.into_iter().map(Cow::Owned).collect();
                let (bonds, bond_spans) =
                    resolve_bonds(self.bonds.as_ref(), &particles, &integrator)?;
                let spans = BodySpans::Particles(spans, bond_spans);
                (particles, bonds, None, spans, species)
            }
            (None, None) => {
                return Err(Issue::unplaced(
                    "the scene has no particles: give [[particle]] tables or a [helix] table",
                ));
            }
        };

        let periodic = match (&self.periodic, suspension) {
            (Some(b), s) => Some(super::periodic::resolve(b, s.map(|(_, e)| e))?),
            (None, Some((_, e))) => Some(super::PeriodicBox {
                size: e,
                method: super::BoxMethod::Auto,
                tolerance: super::DEFAULT_BOX_TOLERANCE,
                method_line: None,
            }),
            (None, None) => None,
        };
        if let Some(b) = &periodic {
            super::periodic::check_particles(b, &particles, &body_span)?;
        }
        check_geometry(&particles, model.overlap, periodic.as_ref(), &body_span)?;
        if let Some(w) = wall {
            super::wall::check_particles(w, &particles, &body_span)?;
        }
        super::precision::check(&particles, &bonds, integrator.precision, &body_span)?;
        if let (Some(raw), Some(thermal)) = (&self.brownian, &brownian) {
            let min_radius = particles.iter().fold(f64::INFINITY, |m, p| m.min(p.radius));
            raw.check_precision(thermal, &integrator, fluid.viscosity, min_radius)?;
        }
        if integrator.method.is_inertial()
            && let Some(k) = particles.iter().position(|p| p.density <= 0.0)
        {
            return Err(issue(
                body_span.density(k),
                format!(
                    "particle {k} has density {} but the inertial method needs positive masses",
                    particles[k].density
                ),
            ));
        }

        let scene = Scene {
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
            brownian,
            species,
            wall,
            periodic,
            suspension: suspension.map(|(s, _)| s),
            floor,
            pinned,
        };
        // "pse" where the scene needs the assembled mobility: placed at the method.
        if let (Err(e), Some(raw)) = (scene.check_box_runs(None), &self.periodic) {
            let at = raw.get_ref().method_at().map(|s| s..s + 1);
            return Err(issue(at.unwrap_or(raw.span()), e.to_string()));
        }
        let keys = super::kernel::KeySpans::of(&self, raw_int.span());
        super::kernel::check(&scene, &keys, &body_span)?;
        Ok(scene)
    }
}

impl RawScene {
    /// The `[suspension]` table's spheres and box edge (the only body: no helix, no
    /// explicit particles or bonds), sized from its count before anything is placed.
    fn generate_suspension(
        &self,
        plans: &[Plan],
        limits: Limits,
        every: usize,
    ) -> Result<(super::Suspension, (Vec<super::Particle>, f64)), Issue> {
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
        let s = super::suspension::resolve(raw)?;
        let at = raw.get_ref().count_span().unwrap_or(raw.span());
        let integrator = self.integrator.as_ref().map(|i| i.get_ref());
        fits(plans, s.count, 0, limits.storage).map_err(|e| too_large(at.clone(), e))?;
        if let Some(i) = integrator {
            let i = resolve_integrator(i)?;
            check_output(&i, every, s.count, limits.output).map_err(|m| issue(at.clone(), m))?;
        }
        let body = s.generate().map_err(|m| issue(raw.span(), m))?;
        Ok((s, body))
    }
}

/// Spans of the body's values, to place geometric errors.
pub(super) enum BodySpans {
    /// A generated body (the helix's or the suspension's table).
    Helix(Range<usize>),
    /// Per particle: span of its position, span of its density (or of its position);
    /// per bond: span of its length (or of its `between`).
    Particles(ParticleSpans, Vec<Range<usize>>),
}

impl BodySpans {
    pub(super) fn position(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v, _) => v[k].0.clone(),
        }
    }

    pub(super) fn density(&self, k: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(v, _) => v[k].1.clone(),
        }
    }

    pub(super) fn bond(&self, l: usize) -> Range<usize> {
        match self {
            BodySpans::Helix(s) => s.clone(),
            BodySpans::Particles(_, b) => b[l].clone(),
        }
    }
}

/// Refuses a run whose trajectory files would exceed `limit` bytes (estimated from the
/// frame count and the particle count, before anything is generated).
fn check_output(integrator: &Integrator, every: usize, n: usize, limit: u64) -> Result<(), String> {
    let frames = (integrator.steps() / every.max(1)) as f64 + 2.0;
    let bytes = frames * crate::sizing::frame_bytes(n);
    if bytes > limit as f64 {
        return Err(format!(
            "{frames:.0} frames of {n} particles make about {} of trajectory files, over the limit of {}; raise [output] every, shorten the duration or use `run --max-output`",
            crate::sizing::human(bytes.min(u64::MAX as f64) as u64),
            crate::sizing::human(limit)
        ));
    }
    Ok(())
}

/// What sizes the scene's storage: its own method, or with `level = "auto"` each method
/// the rules may pick.
fn plans(
    model: &Model,
    integrator: &Integrator,
    flow: &Flow,
    contact: Option<super::Contact>,
    brownian: Option<super::Thermal>,
    wall: bool,
) -> Vec<Plan> {
    let plan = |(method, rotation)| Plan {
        method,
        rotation,
        solver: integrator.solver,
        precision: integrator.precision,
        contact,
        brownian,
        wall,
        matrix_free: integrator.matrix_free,
        compact_products: integrator.compact_products,
        pse: false,
    };
    match model.level {
        Level::Manual => vec![plan((integrator.method, model.rotation))],
        Level::Auto => crate::auto::possible_methods(flow.vorticity)
            .map(plan)
            .to_vec(),
    }
}

fn fits(plans: &[Plan], n: usize, b: usize, limit: usize) -> Result<(), TooLarge> {
    plans
        .iter()
        .try_for_each(|p| p.check(n, b, limit).map(|_| ()))
}

/// Refuses explicit particles and bonds whose storage exceeds `limit`, placed at the
/// first particle (bonds left out) or else the first bond whose count crosses it.
fn check_counts(
    plans: &[Plan],
    ps: &[RawParticle],
    bonds: &[RawBond],
    limit: usize,
) -> Result<(), Issue> {
    let (n, b) = (ps.len(), bonds.len());
    let Err(e) = fits(plans, n, b, limit) else {
        return Ok(());
    };
    let first = (1..=n)
        .map(|k| (k, 0))
        .chain((1..=b).map(|l| (n, l)))
        .find(|&(k, l)| fits(plans, k, l, limit).is_err());
    let span = match first {
        Some((_, l)) if l > 0 => bonds[l - 1].between.span(),
        Some((k, _)) => ps[k - 1].position.span(),
        None => ps[n.saturating_sub(1)].position.span(),
    };
    Err(too_large(span, e))
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
        Some(m) if *m.get_ref() > super::MAX_ITERATIONS => {
            return Err(issue(
                m.span(),
                format!(
                    "max_iterations must be at most {} (it bounds one step's constraint work)",
                    super::MAX_ITERATIONS
                ),
            ));
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
        fene: resolve_fene(r)?,
        matrix_free: r.matrix_free.as_ref().is_some_and(|m| *m.get_ref()),
        compact_products: r.compact_products.unwrap_or(false),
    })
}

/// `fene` (the FENE springs' maximum extension): > 0 and finite, springs only.
fn resolve_fene(r: &RawIntegrator) -> Result<Option<f64>, Issue> {
    let Some(q0) = &r.fene else {
        return Ok(None);
    };
    if r.method != Method::Springs {
        return Err(issue(
            q0.span(),
            "fene (the FENE springs' maximum extension) needs method = \"springs\"",
        ));
    }
    let q = number(&r.fene, 0.0, "fene (maximum extension)", Bound::Positive)?;
    // The kernel squares it in the run's precision.
    let usable = match r.precision.unwrap_or_default() {
        Precision::F32 => {
            let q = q as f32;
            q > 0.0 && (q * q).is_normal()
        }
        Precision::F64 => (q * q).is_normal(),
    };
    if !usable {
        return Err(issue(
            q0.span(),
            format!(
                "fene {} is not usable in the run's precision (its square must be a normal number)",
                crate::output::format_f64(q)
            ),
        ));
    }
    Ok(Some(q))
}

/// The most the ambient rotation may turn the scene in one step, radians. The flow's
/// velocity `Omega x r` enters every method explicitly, so a step grows a radius about
/// the axis by `sqrt(1 + (|Omega| dt)^2)` (first order; Heun's is no better there): past
/// one radian a step no longer follows the rotation at all, and the run spirals out
/// until its precision overflows (issue 33: vorticity 100 at dt 0.1 grew the radius
/// tenfold a step). Refused at the `vorticity` line instead.
pub const MAX_TURN_PER_STEP: f64 = 1.0;

fn check_turn(raw: &RawScene, flow: &Flow, dt: f64) -> Result<(), Issue> {
    let w = flow.vorticity;
    let rate = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let turn = rate * dt;
    match raw.flow.as_ref().and_then(|f| f.vorticity.as_ref()) {
        Some(v) if turn > MAX_TURN_PER_STEP => Err(issue(
            v.span(),
            format!(
                "vorticity turns the scene by {turn} rad per step (|vorticity| {rate} x dt {dt}), \
                 more than {MAX_TURN_PER_STEP}: no method here follows a rotation that fast; \
                 use dt <= {}",
                MAX_TURN_PER_STEP / rate
            ),
        )),
        _ => Ok(()),
    }
}
