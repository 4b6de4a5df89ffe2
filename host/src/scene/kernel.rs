//! The scene as the kernel's first step will see it: built in the run's precision and
//! put to the step's own input checks ([`hydrorattle::check_step`]) and, for FENE
//! springs, to the spring forces at the start ([`hydrorattle::forces::springs`]), so
//! that an input the first step would refuse is refused here, at its line, before any
//! output folder exists. One predicate per concern: the kernel's, not a copy of it.

use std::ops::Range;

use hydrorattle::{BondError, Noise, ParticleError, Real, StepError};

use super::beads::{beads, bonds};
use super::error::{Issue, issue};
use super::raw::RawScene;
use super::resolve::BodySpans;
use super::{Level, Precision, Scene};

/// Where the keys the step checks are written; `fallback` (the `[integrator]` table)
/// places the rest.
pub(super) struct KeySpans {
    keys: Vec<(&'static str, Range<usize>)>,
    fallback: Range<usize>,
}

impl KeySpans {
    /// The spans of `raw`'s keys, by the kernel's parameter names.
    pub(super) fn of(raw: &RawScene, fallback: Range<usize>) -> KeySpans {
        let span = |v: Option<Range<usize>>, name| v.map(|s| (name, s));
        let i = raw.integrator.as_ref().map(|i| i.get_ref());
        let keys = [
            span(fluid(raw, |f| f.viscosity.as_ref()), "viscosity"),
            span(fluid(raw, |f| f.density.as_ref()), "fluid_density"),
            span(
                raw.gravity.as_ref().and_then(|g| sp(&g.acceleration)),
                "gravity",
            ),
            span(
                raw.flow.as_ref().and_then(|f| sp(&f.velocity)),
                "flow_velocity",
            ),
            span(
                raw.flow.as_ref().and_then(|f| sp(&f.vorticity)),
                "vorticity",
            ),
            span(i.map(|i| i.dt.span()), "time"),
            span(i.and_then(|i| sp(&i.tolerance)), "tolerance"),
            span(i.and_then(|i| sp(&i.max_iterations)), "max_iterations"),
            span(i.and_then(|i| sp(&i.stiffness)), "spring_stiffness"),
            span(i.and_then(|i| sp(&i.fene)), "fene"),
            span(
                i.and_then(|i| i.matrix_free.as_ref().map(|m| m.span())),
                "matrix_free",
            ),
            span(raw.brownian.as_ref().and_then(|b| b.sqrt_span()), "noise"),
            span(raw.brownian.as_ref().and_then(|b| b.sqrt_span()), "lanczos"),
            span(
                raw.brownian.as_ref().and_then(|b| b.sqrt_span()),
                "a Cholesky",
            ),
            span(
                raw.brownian.as_ref().and_then(|b| b.temperature_span()),
                "brownian",
            ),
            span(
                raw.brownian.as_ref().and_then(|b| b.temperature_span()),
                "thermal",
            ),
            span(raw.wall.as_ref().map(|w| w.span()), "a wall"),
            span(raw.wall.as_ref().map(|w| w.span()), "wall"),
            span(raw.slit.as_ref().map(|s| s.span()), "a slit"),
            span(raw.slit.as_ref().map(|s| s.span()), "slit"),
            span(raw.contact.as_ref().map(|c| c.span()), "contacts"),
            span(box_span(raw), "a periodic box"),
            span(box_span(raw), "periodic"),
            span(pinned_span(raw), "pinned"),
            span(raw.near_field.as_ref().map(|n| n.span()), "the near field"),
            span(raw.near_field.as_ref().map(|n| n.span()), "near"),
        ];
        KeySpans {
            keys: keys.into_iter().flatten().collect(),
            fallback,
        }
    }

    /// The span of the key a kernel message names first (it starts with the name).
    fn named(&self, message: &str) -> Range<usize> {
        self.keys
            .iter()
            .find(|(name, _)| message.starts_with(name))
            .map_or_else(|| self.fallback.clone(), |(_, s)| s.clone())
    }
}

/// The `[box]` table's `size`, else the table (the suspension's, when it sets the box).
fn box_span(raw: &RawScene) -> Option<Range<usize>> {
    let table = raw.periodic.as_ref();
    let size = table.and_then(|b| b.get_ref().size_span());
    size.or(table.map(|b| b.span()))
        .or(raw.suspension.as_ref().map(|s| s.span()))
}

/// The `[floor]` table, or the first `fixed` key.
fn pinned_span(raw: &RawScene) -> Option<Range<usize>> {
    let fixed = raw.particles.as_ref().and_then(|ps| {
        ps.get_ref()
            .iter()
            .find_map(|p| p.fixed.as_ref().map(|f| f.span()))
    });
    raw.floor.as_ref().map(|f| f.span()).or(fixed)
}

fn sp<T>(v: &super::raw::S<T>) -> Option<Range<usize>> {
    v.as_ref().map(|s| s.span())
}

fn fluid(
    raw: &RawScene,
    key: impl Fn(&super::raw::RawFluid) -> Option<&toml::Spanned<f64>>,
) -> Option<Range<usize>> {
    raw.fluid.as_ref().and_then(key).map(|v| v.span())
}

/// Refuses `scene` where its first step would be refused, at the value at fault.
pub(super) fn check(scene: &Scene, keys: &KeySpans, body: &BodySpans) -> Result<(), Issue> {
    // `level = "auto"` runs the method it picks: check that one.
    let picked;
    let scene = match scene.model.level {
        Level::Auto => {
            picked = crate::auto::apply(scene, &crate::auto::choose(scene));
            &picked
        }
        Level::Manual => scene,
    };
    let f32 = scene.integrator.precision == Precision::F32;
    let squares = |v| match f32 {
        true => squares_finite::<f32>(v),
        false => squares_finite::<f64>(v),
    };
    let found = match f32 {
        true => first_step::<f32>(scene),
        false => first_step::<f64>(scene),
    };
    let precision = match scene.integrator.precision {
        Precision::F32 => "f32",
        Precision::F64 => "f64",
    };
    // Finite components whose squared length overflows: the step and the observables
    // square them (a speed along gravity is `v . g / |g|`).
    let vectors = [
        ("gravity", scene.gravity),
        ("flow_velocity", scene.flow.velocity),
        ("vorticity", scene.flow.vorticity),
    ];
    if let Some((name, v)) = vectors.into_iter().find(|(_, v)| !squares(*v)) {
        return Err(issue(
            keys.named(name),
            format!("{name} {v:?}: its squared length overflows {precision}"),
        ));
    }
    let Err(e) = found else {
        return Ok(());
    };
    let span = match e {
        StepError::Particle(ParticleError::Massless { particle }) => body.density(particle),
        StepError::Particle(
            ParticleError::NonFinite { particle }
            | ParticleError::BadRadius { particle }
            | ParticleError::BadDensity { particle }
            | ParticleError::BelowWall { particle }
            | ParticleError::Unresolved { particle },
        ) => body.position(particle),
        // A helix's bonds are its generator's: the maximum extension is the key at fault.
        StepError::Bond(BondError::Overstretched { .. }) if matches!(body, BodySpans::Helix(_)) => {
            keys.named("fene")
        }
        StepError::Bond(
            BondError::BadLength { bond }
            | BondError::Overstretched { bond, .. }
            | BondError::OutOfRange { bond, .. }
            | BondError::SelfBond { bond, .. },
        ) => body.bond(bond),
        StepError::BadTimeStep => keys.named("time"),
        StepError::BadParameter(name) | StepError::Unsupported(name) => keys.named(name),
        _ => keys.fallback.clone(),
    };
    Err(issue(
        span,
        format!("{e} in {precision} (the first step would refuse it)"),
    ))
}

/// The first step's input checks of `scene` in precision `T`, and its FENE springs'
/// extensions at the start.
fn first_step<T: Real>(scene: &Scene) -> Result<(), StepError> {
    let p = super::beads::params::<T>(scene);
    let mut beads = beads::<T>(&scene.particles, 1.0)?;
    let mut bonds = bonds::<T>(&scene.bonds, beads.len())?;
    let springs = bonds.len();
    bonds.extend(super::beads::pins::<T>(scene));
    let mut noise = Noise::new(0);
    let mut state = beads.state();
    if scene.brownian.is_some() {
        state.noise = Some(&mut noise);
    }
    hydrorattle::check_step(&state, &bonds, &p)?;
    if p.fene.is_some() {
        let mut force = vec![T::V3_ZERO; state.len()];
        hydrorattle::forces::springs(
            &bonds[..springs],
            p.spring_stiffness,
            p.fene,
            state.pos,
            &mut force,
        )?;
    }
    Ok(())
}

/// `|v|^2` is finite in precision `T`.
fn squares_finite<T: Real>(v: [f64; 3]) -> bool {
    let w = T::v3_from(v);
    T::dot(w, w).is_finite()
}
