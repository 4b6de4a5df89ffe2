//! The time loop of a run in precision `T`: storage, state, recording, checkpoints.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use hydrorattle::observables::{StateThresholds, Twist, VerticalFront};
use hydrorattle::{Noise, Params, Real, SoftContact, step_slices_thermal};
use hydrorattle_heap::Buffers;

use super::checkpoint::Checkpoint;
use super::frames::Keeper;
use super::record::{NEAR_VERTICAL_COS, OBSERVABLES_CSV, Observer, Recorder, each_row};
use super::tail::TailSlope;
use super::{
    Beads, BuildError, Front, Observables, RunOptions, RunResult, Summary, bonds, params, snapshot,
};
use crate::progress::Progress;
use crate::scene::{DEFAULT_SEED, Overlap, Scene};
use crate::sizing::{Plan, TooLarge};

/// What a run steps: its particles, bonds and storage.
struct Prepared<T: Real> {
    beads: Beads<T>,
    bonds: Vec<hydrorattle::Bond<T>>,
    store: Buffers<T>,
}

/// The particles, bonds and storage of a run, checked before anything is written.
fn prepare<T: Real>(scene: &Scene, p: &Params<T>, limit: usize) -> Result<Prepared<T>, BuildError> {
    let (n, b) = (scene.particles.len(), scene.bonds.len());
    // Sized first: an oversized scene is refused before any O(N^2) work.
    let layout = Plan::of(scene).check(n, b, limit)?;
    // Thermal noise needs the mobility's factor on top (`Layout::thermal`).
    let layout = match scene.brownian {
        Some(_) => {
            let l = layout.thermal(p.method, n, b);
            let bytes = l.bytes::<T>();
            if bytes > limit {
                return Err(TooLarge {
                    particles: n,
                    bonds: b,
                    bytes: Some(bytes),
                    limit,
                }
                .into());
            }
            l
        }
        None => layout,
    };
    let beads = Beads::<T>::new(&scene.particles, 1.0)?;
    beads.check_pairs(scene.model.overlap == Overlap::Allow)?;
    Ok(Prepared {
        bonds: bonds::<T>(&scene.bonds, n)?,
        beads,
        store: Buffers::try_new(layout)
            .map_err(|_| BuildError::OutOfMemory(layout.bytes::<T>()))?,
    })
}

/// Runs `scene` (its level already applied) from the start or from `from`.
pub(super) fn run_t<T: Real>(
    scene: &Scene,
    name: &str,
    out: Option<&Path>,
    opts: RunOptions,
    from: Option<&Checkpoint>,
) -> Result<RunResult> {
    let p = params::<T>(scene);
    let Prepared {
        mut beads,
        bonds,
        mut store,
    } = prepare::<T>(scene, &p, opts.max_storage)?;
    if let Some(c) = from {
        c.restore(&mut beads)?;
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| crate::output::name_error(dir, e))?;
    }
    // A thread pool only where the kernel cuts the mobility into bands.
    let pool = match hydrorattle::parallel::bands(beads.len()) > 1 && opts.threads != 1 {
        true => Some(hydrorattle_parallel::Threads::new(opts.threads)?),
        false => None,
    };
    let mut ws = match &pool {
        Some(threads) => store.workspace().with_parallel(threads),
        None => store.workspace(),
    };
    let mut noise = Noise::new(scene.brownian.map_or(DEFAULT_SEED, |b| b.seed));
    let contact = scene.contact.and_then(|c| c.soft()).map(|k| SoftContact {
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
    let checkpoint_every = match (opts.checkpoint_every, out) {
        (Some(t), Some(_)) => Some(((t / scene.integrator.dt).round() as usize).max(1)),
        _ => None,
    };
    if checkpoint_every.is_some() && scene.brownian.is_some_and(|b| b.temperature > 0.0) {
        bail!(
            "checkpoints of Brownian runs are not supported (the noise generator's state cannot be saved)"
        );
    }
    let mut rec = Recorder::new(out, scene.topology(), from.map(|c| c.marks))?;
    let mut twist_prev = vec![T::ZERO; beads.len()];
    let mut twist = Twist::new(&mut twist_prev, T::from_f64(0.25));
    let mut tail = TailSlope::new(steps as f64 * scene.integrator.dt);
    let mut series = Vec::new();
    let mass: Vec<T> = (0..beads.len()).map(|i| beads.mass(i)).collect();
    let observer = Observer {
        bonds: &bonds,
        mass: &mass,
        gravity: p.gravity,
        thresholds: StateThresholds::default(),
    };
    let observe = |beads: &Beads<T>, twist: T, iterations: u32, tension: T| {
        Observables::of(beads, &observer, twist, iterations, tension)
    };
    // The stretching front, checked after every step (frames are too far apart).
    let cos_vertical = T::from_f64(NEAR_VERTICAL_COS);
    let mut front_times = vec![-T::ONE; bonds.len()];
    if let Some(c) = from {
        c.restore_front(&mut front_times)?;
    }
    let mut front = VerticalFront::resume(&mut front_times);
    if from.is_none() {
        front.update(&bonds, &beads.pos, p.gravity, cos_vertical, beads.time);
    }
    let initial = snapshot::<T>(&beads.pos, &beads.radius, beads.time);
    // The twist tracker starts from the current positions; a resumed run carries the
    // total on.
    twist.update(&beads.pos, p.gravity);
    let (first, mut last, mut total_iterations) = match from {
        Some(c) => {
            twist.total = T::from_f64(f64::from_bits(c.twist));
            // The recorder has cut the rows back to the checkpoint, under the
            // temporary name: replay them into the twist-rate window (and the series).
            if let Some(dir) = out {
                let rows = crate::output::tmp_path(&dir.join(OBSERVABLES_CSV));
                each_row(&rows, c.marks.csv_bytes, |o| {
                    tail.add(&o);
                    if opts.keep_series {
                        series.push(o);
                    }
                })?;
            }
            (c.step as usize + 1, c.last, c.total_iterations)
        }
        None => {
            let o = observe(&beads, T::ZERO, 0, T::ZERO);
            rec.record(0, &beads, &o)?;
            tail.add(&o);
            if opts.keep_series {
                series.push(o);
            }
            (1, o, 0)
        }
    };
    let mut keeper = Keeper::new(&opts.keep, steps, scene.integrator.dt, beads.len());
    keeper.take(first - 1, &beads);
    let bar = if opts.progress {
        Progress::new(steps as u64, name)
    } else {
        Progress::hidden(steps as u64)
    };
    let start = Instant::now();
    let (mut done, mut failure) = (first - 1, None);
    for s in first..=steps {
        match step_slices_thermal(beads.state(), &bonds, &p, &mut ws, &mut ext, &mut noise) {
            Ok(rep) => {
                done = s;
                keeper.take(s, &beads);
                total_iterations += u64::from(rep.iterations);
                let tw = twist.update(&beads.pos, p.gravity);
                front.update(&bonds, &beads.pos, p.gravity, cos_vertical, beads.time);
                let scheduled = s % every == 0;
                let mut frame = |rec: &mut Recorder| -> Result<Observables> {
                    let o = observe(&beads, tw, rep.iterations, rep.max_tension);
                    rec.record(s as u64, &beads, &o)?;
                    tail.add(&o);
                    if opts.keep_series {
                        series.push(o);
                    }
                    Ok(o)
                };
                if scheduled {
                    last = frame(&mut rec)?;
                }
                // A checkpoint marks the files after the scheduled frames only: the
                // closing frame of a run that ends between frames is not part of a
                // longer run.
                if let (Some(k), Some(dir)) = (checkpoint_every, out) {
                    if s % k == 0 {
                        let marks = rec.marks()?;
                        let precision = scene.integrator.precision;
                        Checkpoint::of(
                            s as u64,
                            precision,
                            &beads,
                            (tw, front.times()),
                            total_iterations,
                            marks,
                            last,
                        )
                        .save(dir)?;
                    }
                }
                if s == steps && !scheduled {
                    last = frame(&mut rec)?;
                }
            }
            Err(e) => {
                log::warn!("{name}: step {s} failed at t = {}: {e}", beads.time);
                failure = Some(format!("step {s} (t = {}): {e}", beads.time.to_f64()));
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
    if last.time != beads.time.to_f64() {
        let o = observe(&beads, twist.total, 0, T::ZERO);
        rec.record(done as u64, &beads, &o)?;
        tail.add(&o);
        if opts.keep_series {
            series.push(o);
        }
        last = o;
    }
    let twist_rate = tail.slope();
    let outcome = match (&failure, tail.late_state()) {
        (None, Some(s)) => s.name().to_string(),
        _ => "failed".to_string(),
    };
    let order = front.order();
    let front = Front {
        cos_min: NEAR_VERTICAL_COS,
        count: order.count,
        correlation: order.correlation.to_f64(),
        first_vertical: front
            .times()
            .iter()
            .map(|t| (*t >= T::ZERO).then(|| t.to_f64()))
            .collect(),
    };
    let stepped = done + 1 - first;
    let summary = Summary {
        particles: beads.len(),
        bonds: bonds.len(),
        tolerance_used: p.solver.tolerance.to_f64(),
        steps,
        steps_done: done,
        wall_time_s: wall,
        steps_per_second: stepped as f64 / wall.max(1e-12),
        mean_iterations: total_iterations as f64 / (done.max(1) as f64),
        final_observables: last,
        twist_rate,
        outcome,
        front,
        failure,
        ..Summary::for_scene(scene, name)
    };
    rec.commit()?;
    let (frames, at) = keeper.finish(done, &beads);
    Ok(RunResult {
        summary,
        initial,
        last: snapshot::<T>(&beads.pos, &beads.radius, beads.time),
        series,
        frames,
        at,
    })
}
