//! Runs a scene on the kernel: precision and capacity dispatch, the time loop,
//! observables, outcome, and the files of a run (`trajectory.xyz`, `observables.csv`,
//! `summary.json`), each written to a temporary name and renamed.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use hydrorattle::observables::{self, Thresholds, Twist};
use hydrorattle::{
    Bond, BondSet, Buffers, Hydro, Layout, Method as KMethod, Params, Particle, ParticleSet, Real,
    SoftContact, Solver as KSolver, SolverKind, step,
};
use serde::Serialize;

use crate::output::{AtomicFile, CsvWriter, XyzWriter, write_json};
use crate::progress::Progress;
use crate::render::Snapshot;
use crate::scene::{Hydrodynamics, Method, Precision, Scene, Solver};

/// Columns of `observables.csv`, in order.
pub const COLUMNS: [&str; 12] = [
    "time",
    "extension",
    "verticality",
    "twist",
    "head_z",
    "head_speed",
    "com_x",
    "com_y",
    "com_z",
    "bond_residual",
    "iterations",
    "max_tension",
];

/// One row of observables.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Observables {
    /// Simulated time.
    pub time: f64,
    /// End-to-end distance over contour length.
    pub extension: f64,
    /// `|cos|` of the head-to-end vector with gravity.
    pub verticality: f64,
    /// Accumulated twist about the vertical through the head (radians).
    pub twist: f64,
    /// Head height.
    pub head_z: f64,
    /// Head settling speed (along gravity).
    pub head_speed: f64,
    /// Centre of mass.
    pub com: [f64; 3],
    /// Largest relative bond-length error.
    pub bond_residual: f64,
    /// Constraint iterations of the last step.
    pub iterations: u32,
    /// Largest bond tension of the last step.
    pub max_tension: f64,
}

impl Observables {
    fn row(&self) -> [f64; 12] {
        [
            self.time,
            self.extension,
            self.verticality,
            self.twist,
            self.head_z,
            self.head_speed,
            self.com[0],
            self.com[1],
            self.com[2],
            self.bond_residual,
            f64::from(self.iterations),
            self.max_tension,
        ]
    }
}

/// What `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Scene name (file stem or case).
    pub scene: String,
    /// Number of particles.
    pub particles: usize,
    /// Number of bonds.
    pub bonds: usize,
    /// The model as run.
    pub model: crate::scene::Model,
    /// The integrator as run.
    pub integrator: crate::scene::Integrator,
    /// Constraint tolerance actually used (raised to what the precision can reach).
    pub tolerance_used: f64,
    /// Contact stiffness (0 when off).
    pub contact_stiffness: f64,
    /// Steps asked for.
    pub steps: usize,
    /// Steps completed (fewer than `steps` when the run failed).
    pub steps_done: usize,
    /// Wall time of the time loop, seconds.
    pub wall_time_s: f64,
    /// Steps per second.
    pub steps_per_second: f64,
    /// Mean constraint iterations per step.
    pub mean_iterations: f64,
    /// Observables at the end.
    pub final_observables: Observables,
    /// Late-time twist rate (slope over the last quarter of the run), rad per time unit.
    pub twist_rate: f64,
    /// Classified outcome: stretched, twisting, other (or failed).
    pub outcome: String,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// What `level = "auto"` chose and why (None for a manual level).
    pub level_choice: Option<crate::auto::Choice>,
}

/// A finished run: summary, first and last configurations, the observables series.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Summary.
    pub summary: Summary,
    /// Initial configuration.
    pub initial: Snapshot,
    /// Final configuration.
    pub last: Snapshot,
    /// Observables every `output.every` steps.
    pub series: Vec<Observables>,
}

/// Options of a run.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    /// Show a progress bar (on a terminal, after a second).
    pub progress: bool,
    /// Stop after at most this many steps (smoke runs); None: the whole duration.
    pub max_steps: Option<usize>,
}

/// Runs `scene`, writing the run's files into `out` when given.
pub fn run(scene: &Scene, name: &str, out: Option<&Path>, opts: RunOptions) -> Result<RunResult> {
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let need = scene.particles.len().max(scene.bonds.len());
    let choice =
        (scene.model.level == crate::scene::Level::Auto).then(|| crate::auto::choose(scene));
    let scene = match &choice {
        Some(c) => {
            log::info!("{name}: level auto: {}", c.reason);
            crate::auto::apply(scene, c)
        }
        None => scene.clone(),
    };
    let name = name.to_string();
    let out = out.map(Path::to_path_buf);
    macro_rules! go {
        ($t:ty, $n:literal) => {{
            // The workspace is on the heap; the particle set is built on this stack.
            let stack = 2 * std::mem::size_of::<ParticleSet<$t, $n>>() + (64 << 20);
            std::thread::Builder::new()
                .stack_size(stack)
                .spawn(move || run_t::<$t, $n>(&scene, &name, out.as_deref(), opts, choice))
                .context("spawning the run thread")?
                .join()
                .map_err(|_| anyhow!("the run thread panicked"))?
        }};
    }
    match (scene.integrator.precision, need) {
        (Precision::F64, 0..=32) => go!(f64, 32),
        (Precision::F64, 33..=128) => go!(f64, 128),
        (Precision::F64, 129..=512) => go!(f64, 512),
        (Precision::F32, 0..=32) => go!(f32, 32),
        (Precision::F32, 33..=128) => go!(f32, 128),
        (Precision::F32, 129..=512) => go!(f32, 512),
        _ => Err(anyhow!(
            "{need} particles or bonds: the demo is built for at most 512"
        )),
    }
}

/// Kernel parameters for a scene in precision `T`.
pub fn params<T: Real>(scene: &Scene) -> Params<T> {
    let i = &scene.integrator;
    let mut p = Params::new(T::from_f64(i.dt));
    p.viscosity = T::from_f64(scene.fluid.viscosity);
    p.fluid_density = T::from_f64(scene.fluid.density);
    p.gravity = T::v3_from(scene.gravity);
    p.flow_velocity = T::v3_from(scene.flow.velocity);
    p.vorticity = T::v3_from(scene.flow.vorticity);
    p.hydro = match scene.model.hydrodynamics {
        Hydrodynamics::Rpy => Hydro::Rpy,
        Hydrodynamics::Oseen => Hydro::Oseen,
        Hydrodynamics::FreeDraining => Hydro::FreeDraining,
    };
    p.method = match i.method {
        Method::Overdamped => KMethod::Overdamped,
        Method::Overdamped2 => KMethod::Overdamped2,
        Method::Rattle => KMethod::Rattle,
        Method::RattleStable => KMethod::RattleStable,
        Method::Springs => KMethod::Springs,
    };
    p.rotation = scene.model.rotation;
    // f32 cannot reach 1e-10: floor the tolerance at a few hundred ulps.
    let floor = 256.0 * T::EPSILON.to_f64();
    p.solver = KSolver {
        kind: match i.solver {
            Solver::Sweep => SolverKind::Sweep,
            Solver::Newton => SolverKind::Newton,
        },
        tolerance: T::from_f64(i.tolerance.max(floor)),
        max_iterations: u32::try_from(i.max_iterations).unwrap_or(u32::MAX),
    };
    p.allow_overlap = scene.model.overlap == crate::scene::Overlap::Allow;
    p.spring_stiffness = T::from_f64(i.stiffness);
    // The paper's explicit drag can shiver silently (bounded, wrong) beyond its limit:
    // the demo refuses such steps up front.
    p.stability_guard = true;
    p
}

fn snapshot<T: Real>(ps: &[T::V3], radius: &[T], time: T) -> Snapshot {
    Snapshot {
        time: time.to_f64(),
        positions: ps.iter().map(|&v| T::v3_to_f64(v)).collect(),
        radii: radius.iter().map(|r| r.to_f64()).collect(),
    }
}

/// Least-squares slope of `y` against `x`.
pub fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if points.len() < 2 {
        return 0.0;
    }
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = points.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx) * (p.0 - mx))
    });
    if den > 0.0 { num / den } else { 0.0 }
}

fn run_t<T: Real, const N: usize>(
    scene: &Scene,
    name: &str,
    out: Option<&Path>,
    opts: RunOptions,
    level_choice: Option<crate::auto::Choice>,
) -> Result<RunResult> {
    let p = params::<T>(scene);
    let n = scene.particles.len();
    let mut ps: Box<ParticleSet<T, N>> = Box::new(ParticleSet::new());
    for (k, q) in scene.particles.iter().enumerate() {
        let part = Particle::new(
            T::v3_from(q.position),
            T::from_f64(q.radius),
            T::from_f64(q.density),
        );
        ps.push(part)
            .map_err(|(_, e)| anyhow!("particle {k}: {e}"))?;
    }
    ps.validate(p.allow_overlap).map_err(|e| anyhow!("{e}"))?;
    let mut bonds: BondSet<T, N> = BondSet::new();
    for b in &scene.bonds {
        let bond = Bond {
            i: b.i,
            j: b.j,
            length: T::from_f64(b.length),
        };
        bonds.push(bond, n).map_err(|(_, e)| anyhow!("{e}"))?;
    }
    let mut ws_store = Buffers::<T>::new(Layout::all(N, N));
    let mut ws = ws_store.workspace();
    let contact = scene.contact.map(|k| SoftContact {
        stiffness: T::from_f64(k),
    });
    let mut ext = |pos: &[T::V3], radius: &[T], force: &mut [T::V3]| {
        if let Some(mut c) = contact {
            hydrorattle::ExternalForce::add(&mut c, pos, radius, force);
        }
    };
    let steps = opts.max_steps.map_or(scene.integrator.steps(), |m| {
        m.min(scene.integrator.steps())
    });
    let every = scene.output.every.max(1);
    let species = scene.species();
    let (mut xyz, mut csv) = match out {
        Some(dir) => (
            Some(XyzWriter::new(AtomicFile::create(
                &dir.join("trajectory.xyz"),
            )?)),
            Some(CsvWriter::new(
                AtomicFile::create(&dir.join("observables.csv"))?,
                &COLUMNS,
            )?),
        ),
        None => (None, None),
    };
    let mut twist: Twist<T, N> = Twist::new(T::from_f64(0.25));
    let mut series = Vec::with_capacity(steps / every + 2);
    let observe = |ps: &ParticleSet<T, N>, twist: T, iterations: u32, tension: T| {
        let pos = &ps.pos[..n];
        let com = observables::centre_of_mass::<T>(pos, |i| ps.mass(i));
        Observables {
            time: ps.time.to_f64(),
            extension: observables::extension::<T>(pos, bonds.as_slice()).to_f64(),
            verticality: observables::verticality::<T>(pos, p.gravity).to_f64(),
            twist: twist.to_f64(),
            head_z: T::xyz(pos[0])[2].to_f64(),
            head_speed: observables::settling_speed::<T>(&ps.vel[..n], 0, p.gravity).to_f64(),
            com: T::v3_to_f64(com),
            bond_residual: bonds.max_residual(pos).1.to_f64(),
            iterations,
            max_tension: tension.to_f64(),
        }
    };
    let mut record = |ps: &ParticleSet<T, N>, o: Observables| -> Result<()> {
        if let Some(w) = xyz.as_mut() {
            let pos: Vec<[f64; 3]> = ps.pos[..n].iter().map(|&v| T::v3_to_f64(v)).collect();
            let vel: Vec<[f64; 3]> = ps.vel[..n].iter().map(|&v| T::v3_to_f64(v)).collect();
            let rad: Vec<f64> = ps.radius[..n].iter().map(|r| r.to_f64()).collect();
            w.write_frame(o.time, &species, &pos, &rad, &vel)?;
        }
        if let Some(c) = csv.as_mut() {
            c.write_row(&o.row())?;
        }
        Ok(())
    };
    let initial = snapshot::<T>(&ps.pos[..n], &ps.radius[..n], ps.time);
    twist.update(&ps.pos[..n], p.gravity);
    let first = observe(&ps, T::ZERO, 0, T::ZERO);
    record(&ps, first)?;
    series.push(first);
    let bar = if opts.progress {
        Progress::new(steps as u64, name)
    } else {
        Progress::hidden(steps as u64)
    };
    let start = Instant::now();
    let (mut done, mut failure, mut total_iterations) = (0usize, None, 0u64);
    for s in 1..=steps {
        match step(&mut ps, &bonds, &p, &mut ws, &mut ext) {
            Ok(rep) => {
                done = s;
                total_iterations += u64::from(rep.iterations);
                let tw = twist.update(&ps.pos[..n], p.gravity);
                if s % every == 0 || s == steps {
                    let o = observe(&ps, tw, rep.iterations, rep.max_tension);
                    record(&ps, o)?;
                    series.push(o);
                }
            }
            Err(e) => {
                log::warn!("{name}: step {s} failed at t = {}: {e}", ps.time);
                failure = Some(format!("step {s} (t = {}): {e}", ps.time.to_f64()));
                break;
            }
        }
        if s % 256 == 0 {
            bar.set_position(s as u64);
        }
    }
    bar.finish();
    let wall = start.elapsed().as_secs_f64();
    // Close the state: a final row when the run stopped between frames.
    let last_obs = observe(&ps, twist.total, 0, T::ZERO);
    if series.last().map(|o| o.time) != Some(last_obs.time) {
        record(&ps, last_obs)?;
        series.push(last_obs);
    }
    let tail: Vec<(f64, f64)> = series[series.len() * 3 / 4..]
        .iter()
        .map(|o| (o.time, o.twist))
        .collect();
    let twist_rate = slope(&tail);
    let th = Thresholds::<f64>::default();
    let outcome = match failure {
        Some(_) => "failed".to_string(),
        None => observables::classify(last_obs.verticality, last_obs.extension, twist_rate, &th)
            .name()
            .to_string(),
    };
    let summary = Summary {
        scene: name.to_string(),
        particles: n,
        bonds: bonds.len(),
        model: scene.model,
        integrator: scene.integrator,
        tolerance_used: p.solver.tolerance.to_f64(),
        contact_stiffness: scene.contact.unwrap_or(0.0),
        steps,
        steps_done: done,
        wall_time_s: wall,
        steps_per_second: done as f64 / wall.max(1e-12),
        mean_iterations: total_iterations as f64 / (done.max(1) as f64),
        final_observables: last_obs,
        twist_rate,
        outcome,
        failure,
        level_choice,
    };
    if let Some(dir) = out {
        if let Some(w) = xyz {
            w.into_inner().commit()?;
        }
        if let Some(c) = csv {
            c.into_inner().commit()?;
        }
        write_json(&dir.join("summary.json"), &summary)?;
    }
    Ok(RunResult {
        summary,
        initial,
        last: snapshot::<T>(&ps.pos[..n], &ps.radius[..n], ps.time),
        series,
    })
}
