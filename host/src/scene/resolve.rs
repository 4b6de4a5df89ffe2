//! From the raw form to a [`Scene`]: defaults filled in, numbers and geometry checked,
//! the helix generated, each error placed at the value at fault. The storage a scene
//! needs is checked from its counts before anything is generated or pair-checked.
//!
//! This file holds the order of the checks (which error a scene with several faults
//! reports) and the tables that need nothing else. The body (the helix, the
//! suspension and its floor, or explicit particles and bonds) is resolved in
//! `resolve/body.rs`, the `[integrator]` table in `resolve/integrator.rs`, and the
//! storage and output budgets the body is sized against, from its counts alone, in
//! `resolve/budget.rs`: each is a table (or a limit) with its own defaults and errors,
//! and the body needs the other two before it generates anything.

mod body;
mod budget;
mod integrator;

pub(super) use body::BodySpans;
pub use integrator::MAX_TURN_PER_STEP;

use budget::plans;
use integrator::{check_turn, resolve_integrator};

use super::bodies::check_geometry;
use super::error::{Issue, issue};
use super::raw::{Bound, RawScene, number, vector};
use super::{Flow, Fluid, Level, Method, Model, Output, Scene, Sqrt, TARGET_FRAMES};
use crate::sizing::Limits;

impl RawScene {
    /// The scene, refused when its step storage or its output would exceed `limits`.
    pub(super) fn resolve(self, limits: Limits) -> Result<Scene, Issue> {
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
                hydrodynamics: m.hydrodynamics.map_or_else(Default::default, |h| h.0),
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
            let runs = matches!(
                integrator.method,
                Method::Overdamped | Method::Overdamped2 | Method::Springs
            );
            if !runs || model.level != Level::Manual {
                return Err(issue(
                    m.span(),
                    "matrix_free needs method = \"overdamped\", \"overdamped2\" or \"springs\" and level = \"manual\" \
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
            super::contact::check_method(c, raw, &integrator)?;
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
        let slit = match &self.slit {
            None => None,
            Some(raw) => {
                let s = super::slit::resolve(raw)?;
                let others = [
                    (self.wall.is_some(), "[wall]"),
                    (
                        self.periodic.is_some() || self.suspension.is_some(),
                        "[box]",
                    ),
                ];
                super::slit::check(raw, &model, &integrator, others)?;
                Some(s)
            }
        };
        let near_field = match &self.near_field {
            None => None,
            Some(raw) => Some(super::near::resolve(raw, &model)?),
        };
        let free_space = match &self.free_space {
            None => None,
            Some(raw) => Some(super::free_space::resolve(
                raw,
                &super::free_space::Context {
                    model: &model,
                    integrator: &integrator,
                    brownian,
                    // A slit's mobility is its walls' too.
                    wall: (self.wall.as_ref().map(|w| w.span()))
                        .or(self.slit.as_ref().map(|s| s.span())),
                    periodic: self.periodic.as_ref().map(|b| b.span()),
                },
            )?),
        };
        // The fast product gives products only: its run is matrix-free.
        let fast = free_space.and_then(|f| f.fast_tolerance()).is_some();
        let mut integrator = integrator;
        integrator.matrix_free |= fast;
        // "auto" may take the fast product: sized as it would be (`free_cost::choose`
        // checks each path's storage when the run starts).
        let fast = free_space.is_some_and(|f| f.may_be_fast());
        let every = match self.output.as_ref().and_then(|o| o.every.as_ref()) {
            None => integrator.steps().div_ceil(TARGET_FRAMES).max(1),
            Some(e) if *e.get_ref() == 0 => {
                return Err(issue(e.span(), "every must be >= 1 (steps between frames)"));
            }
            // Past the last step `every` changes nothing: held at the step count, it
            // stays a number a scene file can hold.
            Some(e) => (*e.get_ref()).min(integrator.steps()),
        };
        // A box PSE will sum (named, or "auto" where products suffice: the sizes where
        // storage matters are PSE's) is sized without the stored mobility; its grid is
        // checked once the box is known (`box_cost::check_pse`).
        let products =
            super::periodic::needs_matrix(&model, &integrator, brownian, near_field.is_some())
                .is_none();
        let pse = match self.periodic.as_ref().map(|b| b.get_ref().method()) {
            Some(super::BoxMethod::Pse) => true,
            Some(super::BoxMethod::Auto) => products,
            _ => false,
        };
        let plans = plans(
            &model,
            &integrator,
            &flow,
            contact,
            brownian,
            (
                (wall.is_some(), slit.is_some()),
                pse,
                near_field.is_some(),
                fast,
            ),
        );
        let every_span = self
            .output
            .as_ref()
            .and_then(|o| o.every.as_ref())
            .map(|e| e.span());
        let output_span = every_span.unwrap_or_else(|| raw_int.get_ref().duration.span());
        let body = self.body(&plans, limits, &integrator, every, output_span)?;

        let periodic = match (&self.periodic, body.suspension) {
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
            super::periodic::check_particles(b, &body.particles, &body.spans)?;
        }
        if let (Some(b), Some(raw)) = (&periodic, &self.periodic) {
            let counts = (&body.particles[..], body.bonds.len());
            super::box_cost::check_pse(b, raw, counts, &plans, limits.storage)?;
        }
        check_geometry(
            &body.particles,
            model.overlap,
            periodic.as_ref(),
            &body.spans,
        )?;
        if let Some(w) = wall {
            super::wall::check_particles(w, &body.particles, &body.spans)?;
        }
        if let Some(s) = slit {
            super::slit::check_particles(s, &body.particles, &body.spans)?;
        }
        super::precision::check(
            &body.particles,
            &body.bonds,
            integrator.precision,
            &body.spans,
        )?;
        if let (Some(raw), Some(thermal)) = (&self.brownian, &brownian) {
            let min_radius = body
                .particles
                .iter()
                .fold(f64::INFINITY, |m, p| m.min(p.radius));
            raw.check_precision(thermal, &integrator, fluid.viscosity, min_radius)?;
        }
        if matches!(integrator.method, Method::Rattle | Method::RattleStable)
            && let Some(k) = body.particles.iter().position(|p| p.density <= 0.0)
        {
            return Err(issue(
                body.spans.density(k),
                format!(
                    "particle {k} has density {} but the inertial method needs positive masses",
                    body.particles[k].density
                ),
            ));
        }

        let scene = Scene {
            fluid,
            gravity,
            flow,
            particles: body.particles,
            bonds: body.bonds,
            helix: body.helix,
            model,
            integrator,
            output: Output { every },
            contact,
            brownian,
            species: body.species,
            wall,
            slit,
            periodic,
            suspension: body.suspension.map(|(s, _)| s),
            cloud: body.cloud,
            free_space,
            floor: body.floor,
            pinned: body.pinned,
            near_field,
        };
        // "pse" where the scene needs the assembled mobility: placed at the method.
        if let (Err(e), Some(raw)) = (scene.check_box_runs(None), &self.periodic) {
            let at = raw.get_ref().method_at().map(|s| s..s + 1);
            return Err(issue(at.unwrap_or(raw.span()), e.to_string()));
        }
        let keys = super::kernel::KeySpans::of(&self, raw_int.span());
        super::kernel::check(&scene, &keys, &body.spans)?;
        Ok(scene)
    }
}
