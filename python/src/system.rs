//! A system stepped by the kernel: the host library's [`Engine`] in f64 or f32
//! ([`AnyEngine`]), with NumPy getters (copies) and `step(n)` run with the GIL released.

use hydrorattle::{Bond, Noise, Real, StepReport};
use hydrorattle_host::each_engine;
use hydrorattle_host::scene::{Precision, Scene};
use hydrorattle_host::sim::retry::Retries;
use hydrorattle_host::sim::{AnyEngine, Beads, Engine, Saved, resolve_level};
use hydrorattle_host::sizing::DEFAULT_LIMIT;
use numpy::ndarray::{Array1, Array2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{bond_error, scene_error, value_error};
use crate::input::{column, in_box, is_f32, rows, spheres};
use crate::params::params_from;
use crate::shared::Shared;
use crate::stepping::{Every, steps};

/// The report of the last step.
#[pyclass(module = "hydrorattle", frozen, get_all)]
#[derive(Clone, Copy, Debug)]
pub struct Report {
    /// Position-constraint iterations of the final solve.
    pub iterations: u32,
    /// Velocity-constraint iterations (RATTLE stage), 0 where there is none.
    pub velocity_iterations: u32,
    /// Largest relative bond-length error after the step.
    pub residual: f64,
    /// Largest bond tension magnitude (force units).
    pub max_tension: f64,
    /// Hard-sphere contacts held at the end of the step.
    pub contacts: u32,
    /// Spheres held on the wall at the end of the step (0 without a wall).
    pub wall_contacts: u32,
    /// Active-set rounds of the contact projection.
    pub contact_rounds: u32,
    /// Lanczos iterations of the thermal noise (0 with Cholesky or without noise).
    pub noise_iterations: u32,
    /// Steps made by this call.
    pub steps: usize,
    /// Steps of this call the kernel refused at full length and that were made as 2,
    /// 4, ... shorter steps along a Brownian bridge instead (thermal runs only; the
    /// CLI's `retried_steps`).
    pub retried_steps: u64,
    /// The shorter steps those retries took.
    pub retry_substeps: u64,
}

#[pymethods]
impl Report {
    fn __repr__(&self) -> String {
        format!(
            "Report(steps={}, iterations={}, residual={:e}, max_tension={}, contacts={}, retried_steps={})",
            self.steps,
            self.iterations,
            self.residual,
            self.max_tension,
            self.contacts,
            self.retried_steps
        )
    }
}

impl Report {
    /// The report of step `steps` of a call, `r` the kernel's, with the retries of the
    /// call so far (`retried`: the engine's count now less at the call's start).
    pub fn of<T: Real>(r: &StepReport<T>, steps: usize, retried: Retries) -> Self {
        Report {
            iterations: r.iterations,
            velocity_iterations: r.velocity_iterations,
            residual: r.residual.to_f64(),
            max_tension: r.max_tension.to_f64(),
            contacts: r.contacts,
            wall_contacts: r.wall_contacts,
            contact_rounds: r.contact_rounds,
            noise_iterations: r.noise_iterations,
            steps,
            retried_steps: retried.steps,
            retry_substeps: retried.substeps,
        }
    }
}

/// The Rust side of `hydrorattle.System`: the engine shared between Python threads
/// ([`Shared`]: reads from other threads while it steps wait for the end of the step).
#[pyclass(module = "hydrorattle", frozen)]
pub struct Core {
    shared: Shared<AnyEngine>,
}

impl Core {
    fn of(inner: AnyEngine) -> Core {
        Core {
            shared: Shared::new(inner),
        }
    }
}

/// `(N, 3)` rows in precision `T` as a float64 array.
pub fn rows_f64<'py, T: Real>(py: Python<'py>, v: &[T::V3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flat_map(|&x| T::v3_to_f64(x)).collect();
    Array2::from_shape_vec((v.len(), 3), flat)
        .expect("3 values per row")
        .into_pyarray(py)
}

/// Values in precision `T` as a float64 array.
fn values_f64<'py, T: Real>(py: Python<'py>, v: &[T]) -> Bound<'py, PyArray1<f64>> {
    Array1::from_iter(v.iter().map(|x| x.to_f64())).into_pyarray(py)
}

/// The engine of explicit arrays in precision `T`.
#[allow(clippy::too_many_arguments)]
fn engine_from<T: Real>(
    py: Python<'_>,
    pos: &[[f64; 3]],
    radii: &[f64],
    densities: &[f64],
    bonds: &[[i64; 2]],
    lengths: Option<&[f64]>,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<Engine<T>> {
    let (params, extras) = params_from::<T>(kw)?;
    if let Some(c) = params.periodic {
        in_box::<T>(py, c.size().map(|l| l.to_f64()), pos, radii)?;
    }
    let (p, r) = spheres::<T>(py, pos, radii, Some(densities))?;
    let n = p.len();
    let index = |k: usize, i: i64| -> PyResult<usize> {
        usize::try_from(i).ok().filter(|&i| i < n).ok_or_else(|| {
            PyValueError::new_err(format!("bond {k}: particle index {i} out of range"))
        })
    };
    let mut links = Vec::with_capacity(bonds.len());
    for (k, &[i, j]) in bonds.iter().enumerate() {
        let (i, j) = (index(k, i)?, index(k, j)?);
        // Measured in f64 (as a scene file's bonds are), then rounded to `T`.
        let length = match lengths {
            Some(l) => l[k],
            None => {
                let d: Vec<f64> = (0..3).map(|c| pos[i][c] - pos[j][c]).collect();
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            }
        };
        links.push(Bond {
            i,
            j,
            length: T::from_f64(length),
        });
    }
    hydrorattle::bonds::validate(&links, n).map_err(|e| bond_error(py, e))?;
    let density = densities.iter().map(|&d| T::from_f64(d)).collect();
    let beads = Beads::at_rest(p, r, density);
    let noise = Noise::new(extras.seed);
    let engine = Engine::from_parts(beads, links, params, noise, None, DEFAULT_LIMIT)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    ready(py, engine, extras.threads)
}

/// `e` checked as its first step would check it (a refusal is a `ValueError` with the
/// kernel's message and `kind`), on `threads` threads.
fn ready<T: Real>(py: Python<'_>, mut e: Engine<T>, threads: usize) -> PyResult<Engine<T>> {
    e.check().map_err(|k| value_error(py, k))?;
    e.with_threads(threads)
        .map_err(|err| PyValueError::new_err(format!("threads: {err}")))
}

/// The engine of a scene (its level resolved), in the scene's precision.
fn engine_of_scene(py: Python<'_>, scene: &Scene) -> PyResult<AnyEngine> {
    let (scene, _) = resolve_level(scene, "scene");
    let engine =
        AnyEngine::new(&scene, DEFAULT_LIMIT).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(each_engine!(engine, e, _T => ready(py, e, 0)?.into()))
}

#[pymethods]
impl Core {
    /// A system of explicit particles and bonds; see `hydrorattle.System`.
    #[staticmethod]
    #[pyo3(signature = (positions, radii, densities, bonds, lengths, precision, params))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        positions: PyReadonlyArray2<'_, f64>,
        radii: PyReadonlyArray1<'_, f64>,
        densities: PyReadonlyArray1<'_, f64>,
        bonds: PyReadonlyArray2<'_, i64>,
        lengths: Option<PyReadonlyArray1<'_, f64>>,
        precision: &str,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Core> {
        let pos = rows(&positions, "positions")?;
        let n = pos.len();
        let radii = column(&radii, "radii", n)?;
        let densities = column(&densities, "densities", n)?;
        let flat = bonds
            .as_slice()
            .map_err(|_| PyValueError::new_err("bonds must be C-contiguous"))?;
        let (pairs, rest) = flat.as_chunks::<2>();
        if !rest.is_empty() || bonds.shape()[1] != 2 {
            return Err(PyValueError::new_err("bonds must have shape (B, 2)"));
        }
        let lengths = match &lengths {
            Some(l) => Some(column(l, "lengths", pairs.len())?),
            None => None,
        };
        let inner = if is_f32(precision)? {
            AnyEngine::F32(engine_from(
                py, pos, radii, densities, pairs, lengths, params,
            )?)
        } else {
            AnyEngine::F64(engine_from(
                py, pos, radii, densities, pairs, lengths, params,
            )?)
        };
        Ok(Core::of(inner))
    }

    /// The system of a scene file, read by the CLI's parser.
    #[staticmethod]
    fn from_scene_file(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Core> {
        let scene = Scene::from_path(&path).map_err(|e| scene_error(py, &e))?;
        Ok(Core::of(engine_of_scene(py, &scene)?))
    }

    /// The system of scene text (TOML), read by the CLI's parser; `origin` names it.
    #[staticmethod]
    fn from_scene_text(py: Python<'_>, text: &str, origin: &str) -> PyResult<Core> {
        let scene = Scene::parse(text, origin).map_err(|e| scene_error(py, &e))?;
        Ok(Core::of(engine_of_scene(py, &scene)?))
    }

    /// `n` steps; the last step's report. `callback()` runs after every `every`-th
    /// step (GIL held, the system readable).
    #[pyo3(signature = (n=1, force=None, callback=None, every=1))]
    fn step(
        &self,
        py: Python<'_>,
        n: usize,
        force: Option<Bound<'_, PyAny>>,
        callback: Option<Py<PyAny>>,
        every: usize,
    ) -> PyResult<Report> {
        if every == 0 {
            return Err(PyValueError::new_err("every must be >= 1"));
        }
        let every = callback.map(|callback| Every { callback, every });
        steps(py, &self.shared, n, force.as_ref(), every)
    }

    /// Positions `(N, 3)`, a float64 copy.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => rows_f64::<T>(py, &e.beads.pos)))
    }

    /// Velocities `(N, 3)`, a float64 copy.
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => rows_f64::<T>(py, &e.beads.vel)))
    }

    /// Angular velocities `(N, 3)`, a float64 copy.
    #[getter]
    fn spins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => rows_f64::<T>(py, &e.beads.omega)))
    }

    /// Radii `(N,)`, a float64 copy.
    #[getter]
    fn radii<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => values_f64::<T>(py, &e.beads.radius)))
    }

    /// Densities `(N,)`, a float64 copy.
    #[getter]
    fn densities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => values_f64::<T>(py, &e.beads.density)))
    }

    /// Bonds `(B, 2)`, an int64 copy.
    #[getter]
    fn bonds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => {
            let _: Option<T> = None;
            let flat: Vec<i64> = e.bonds.iter().flat_map(|b| [b.i as i64, b.j as i64]).collect();
            Array2::from_shape_vec((e.bonds.len(), 2), flat).expect("2 per row").into_pyarray(py)
        }))
    }

    /// Bond lengths `(B,)`, a float64 copy.
    #[getter]
    fn lengths<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => {
            let l: Vec<T> = e.bonds.iter().map(|b| b.length).collect();
            values_f64::<T>(py, &l)
        }))
    }

    /// Bond tensions `(B,)` after the last accepted step, a float64 copy (force units;
    /// positive when the bond pulls its ends together; rigid bonds: `-lambda_k d_k`,
    /// springs: the spring law at the current length). `None` before the first step
    /// and for `overdamped2`, whose last projection's multipliers are only a correction.
    #[getter]
    fn tensions<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        Ok(
            each_engine!(&*self.shared.read(py)?, e, T => e.tensions().map(|t| values_f64::<T>(py, &t))),
        )
    }

    /// Simulated time.
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => { let t: T = e.beads.time; t.to_f64() }))
    }

    /// Time step.
    #[getter]
    fn dt(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => { let t: T = e.params.dt; t.to_f64() }))
    }

    /// The periodic box's edges `(Lx, Ly, Lz)`, or None.
    #[getter]
    fn cell(&self, py: Python<'_>) -> PyResult<Option<[f64; 3]>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => {
            e.params.periodic.map(|c| c.size().map(|l: T| l.to_f64()))
        }))
    }

    /// "f64" or "f32".
    #[getter]
    fn precision(&self, py: Python<'_>) -> PyResult<&'static str> {
        Ok(match self.shared.read(py)?.precision() {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        })
    }

    /// Replaces the positions, velocities, spins and time given (each `(N, 3)` or a
    /// float), checked as the kernel checks a particle (finite values): all or nothing.
    #[pyo3(signature = (positions=None, velocities=None, spins=None, time=None))]
    fn set_state(
        &self,
        py: Python<'_>,
        positions: Option<PyReadonlyArray2<'_, f64>>,
        velocities: Option<PyReadonlyArray2<'_, f64>>,
        spins: Option<PyReadonlyArray2<'_, f64>>,
        time: Option<f64>,
    ) -> PyResult<()> {
        let mut guard = self.shared.write(py)?;
        let n = each_engine!(&*guard, e, T => { let _: Option<T> = None; e.beads.len() });
        let mut new: [Option<&[[f64; 3]]>; 3] = [None; 3];
        let given = [
            ("positions", &positions),
            ("velocities", &velocities),
            ("spins", &spins),
        ];
        for (slot, (what, a)) in new.iter_mut().zip(given) {
            if let Some(a) = a {
                let v = rows(a, what)?;
                if v.len() != n {
                    return Err(PyValueError::new_err(format!(
                        "{what} must have shape ({n}, 3), not ({}, 3)",
                        v.len()
                    )));
                }
                if let Some(k) = v.iter().position(|x| !x.iter().all(|c| c.is_finite())) {
                    return Err(PyValueError::new_err(format!(
                        "particle {k}: non-finite {what}"
                    )));
                }
                *slot = Some(v);
            }
        }
        if let Some(t) = time.filter(|t| !t.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "time must be finite, not {t}"
            )));
        }
        each_engine!(&mut *guard, e, T => {
            let b = &mut e.beads;
            for (v, dst) in new.iter().zip([&mut b.pos, &mut b.vel, &mut b.omega]) {
                if let Some(v) = v {
                    for (d, &x) in dst.iter_mut().zip(v.iter()) {
                        *d = T::v3_from(x);
                    }
                }
            }
            if let Some(t) = time {
                b.time = T::from_f64(t);
            }
            Ok(())
        })
    }

    /// The whole system as JSON text (state, bonds, parameters, noise generator,
    /// counters, the last tensions; every float's bits): what pickling carries.
    fn save_json(&self, py: Python<'_>) -> PyResult<String> {
        let saved = self.shared.read(py)?.save();
        serde_json::to_string(&saved).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The system [`Core::save_json`] wrote.
    #[staticmethod]
    fn restore_json(text: &str) -> PyResult<Core> {
        let saved: Saved = serde_json::from_str(text)
            .map_err(|e| PyValueError::new_err(format!("saved system: {e}")))?;
        Ok(Core::of(
            AnyEngine::restore(&saved).map_err(PyValueError::new_err)?,
        ))
    }

    /// An independent copy of the system (state, storage, noise generator).
    fn copy(&self, py: Python<'_>) -> PyResult<Core> {
        Ok(Core::of(self.shared.read(py)?.clone()))
    }

    /// The state's bits (positions, velocities, spins, time, then the noise
    /// generator's next draw on a copy), for exact comparisons.
    fn state_bits(&self, py: Python<'_>) -> PyResult<Vec<u64>> {
        Ok(each_engine!(&*self.shared.read(py)?, e, T => {
            let mut out = Vec::new();
            for v in [&e.beads.pos, &e.beads.vel, &e.beads.omega] {
                for &x in v.iter() {
                    out.extend(T::v3_to_f64(x).map(f64::to_bits));
                }
            }
            out.push(e.beads.time.to_f64().to_bits());
            out.push(e.noise.clone().normal().to_bits());
            out
        }))
    }
}
