//! From the raw form to a [`Scene`]: defaults filled in, numbers and geometry checked,
//! the helix generated, each error placed at the value at fault. The storage a scene
//! needs is checked from its counts before anything is generated or pair-checked.

use std::ops::Range;

use toml::Spanned;

use super::error::{Issue, issue, too_large};
use super::raw::{
    Bound, RawBond, RawHelix, RawIntegrator, RawParticle, RawScene, distance, finite_vector,
    number, vector,
};
use super::{
    Bond, DEFAULT_DENSITY, Flow, Fluid, Helix, Integrator, Level, Model, Output, Overlap, Particle,
    Scene, TARGET_FRAMES,
};
use crate::sizing::{Plan, TooLarge};

impl RawScene {
    /// The scene, refused when its step storage would exceed `limit` bytes.
    pub(super) fn resolve(self, limit: usize) -> Result<Scene, Issue> {
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
            return Err(Issue::unplaced(
                "missing table [integrator] (method, dt and duration are required)",
            ));
        };
        let integrator = resolve_integrator(raw_int.get_ref())?;
        let brownian = match &self.brownian {
            None => None,
            Some(b) => Some(b.resolve(&model, &integrator)?),
        };
        let every = match self.output.as_ref().and_then(|o| o.every.as_ref()) {
            None => integrator.steps().div_ceil(TARGET_FRAMES).max(1),
            Some(e) if *e.get_ref() == 0 => {
                return Err(issue(e.span(), "every must be >= 1 (steps between frames)"));
            }
            Some(e) => *e.get_ref(),
        };
        let plans = plans(&model, &integrator, &flow);

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
                // Sized from the count alone: a helix too large to run is never generated.
                let at = h.get_ref().tails.as_ref().map_or(h.span(), |t| t.span());
                fits(&plans, helix.tails.saturating_add(1), helix.tails, limit)
                    .map_err(|e| too_large(at, e))?;
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
                let raw_bonds = self.bonds.as_ref().map_or(&[][..], |b| b.get_ref());
                check_counts(&plans, ps.get_ref(), raw_bonds, limit)?;
                let bonds = resolve_bonds(self.bonds.as_ref(), &particles)?;
                (particles, bonds, None, BodySpans::Particles(spans))
            }
            (None, None) => {
                return Err(Issue::unplaced(
                    "the scene has no particles: give [[particle]] tables or a [helix] table",
                ));
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
            brownian,
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

/// What sizes the scene's storage: its own method, or with `level = "auto"` each method
/// the rules may pick.
fn plans(model: &Model, integrator: &Integrator, flow: &Flow) -> Vec<Plan> {
    let plan = |(method, rotation)| Plan {
        method,
        rotation,
        solver: integrator.solver,
        precision: integrator.precision,
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
