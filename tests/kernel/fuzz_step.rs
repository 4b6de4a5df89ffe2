//! Fuzzing `step_slices` with a fixed seed: hostile particles (NaN, infinities, huge,
//! subnormal, zero and negative radii, nested and overlapping spheres), hostile bonds
//! (out of range, self, duplicate, lengths whose square overflows), hostile parameters
//! (every method, solver and mobility; NaN, negative and huge time steps, tolerances,
//! viscosities, gravity, time; rest length zero), every table of the step (rotation,
//! matrix-free products, hard contacts with capacities past `DENSE_BONDS_MAX` rows, a
//! wall, a periodic box (its mobility by the Ewald sum or by PSE), FENE springs, thermal noise by Cholesky, Lanczos or `Auto` with either drift)
//! and mismatched or undersized storage. Every call must return without a panic; a
//! refused step must leave the state and the noise generator bit-identical; an
//! accepted one must leave it finite with the time advanced.
//!
//! 100 000 cases per precision by default (`FUZZ_CASES`, `FUZZ_SEED` to change; a longer run is
//! documented in docs/VALIDATION.md).

use crate::common;

use common::fuzz::{Rng, report, settings};
use common::*;
use hydrorattle::{
    Bond, Brownian, Contacts, Drift, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, Params,
    Periodic, Real, SolverKind, State, Wall, step_slices,
};
use hydrorattle_heap::Buffers;

/// The case's generator; in a hostile case, some values it draws are hostile.
struct Draw(Rng, bool);

impl Draw {
    fn below(&mut self, n: u64) -> u64 {
        self.0.below(n as usize) as u64
    }

    fn unit(&mut self) -> f64 {
        self.0.unit()
    }

    fn next(&mut self) -> u64 {
        self.0.next()
    }

    /// Values near `typical`; in a hostile case, one draw in eight is hostile.
    fn value(&mut self, typical: f64) -> f64 {
        if !self.1 || self.below(8) != 0 {
            return typical * (0.5 + self.unit());
        }
        match self.below(12) {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            3 => 0.0,
            4 => -typical,
            5 => 1e300,
            6 => 5e-324,
            7 => 1e-30,
            8 => f64::from_bits(self.next()),
            9 => 1e20,
            _ => typical * (0.5 + self.unit()),
        }
    }

    fn vec3(&mut self, typical: f64) -> [f64; 3] {
        if self.1 && self.below(4) == 0 {
            [
                self.value(typical),
                self.value(typical),
                self.value(typical),
            ]
        } else {
            [
                typical * (self.unit() - 0.5),
                typical * (self.unit() - 0.5),
                typical * (self.unit() - 0.5),
            ]
        }
    }
}

const SOLVERS: [SolverKind; 4] = [
    SolverKind::Auto,
    SolverKind::Sweep,
    SolverKind::Newton,
    SolverKind::Krylov,
];
const NOISE_SQRT: [NoiseSqrt; 3] = [NoiseSqrt::Auto, NoiseSqrt::Cholesky, NoiseSqrt::Lanczos];
const HYDRO: [Hydro; 3] = [Hydro::Rpy, Hydro::Oseen, Hydro::FreeDraining];

fn bits<T: Real>(v: &[T::V3]) -> Vec<u64> {
    v.iter()
        .flat_map(|&x| f64s::<T>(x))
        .map(f64::to_bits)
        .collect()
}

/// PSE's arrays (complex values, indices, vectors) as the step sizes them, when the box
/// is summed by PSE; a grid past a few million points gets none (the step refuses that,
/// typed).
type PseArrays<T> = hydrorattle_heap::PseBuffers<T>;

#[cfg(feature = "pse")]
fn pse_arrays<T: Real>(p: &Params<T>, radius: &[T]) -> Option<PseArrays<T>> {
    let s = hydrorattle::integrate::pse_storage(p, radius)
        .ok()
        .flatten()?;
    (s.complex <= 1 << 22).then(|| PseArrays::new(s))
}

#[cfg(not(feature = "pse"))]
fn pse_arrays<T: Real>(_: &Params<T>, _: &[T]) -> Option<PseArrays<T>> {
    None
}

/// One fuzz case in precision `T`: whether the step was accepted and whether it had
/// PSE's storage, or `Err` describing a broken promise.
fn case<T: Real>(rng: &mut Draw) -> Result<(bool, bool), String> {
    // Mostly small; one case in eight long enough for more than `DENSE_BONDS_MAX` rows.
    let n = if rng.below(8) == 0 {
        1 + rng.below(40) as usize
    } else {
        1 + rng.below(6) as usize
    };
    // Mostly a chain along x with gaps, so that many cases are valid and step.
    let mut pos = Vec::with_capacity(n);
    let mut radius = Vec::with_capacity(n);
    for k in 0..n {
        let r = if rng.1 && rng.below(10) == 0 {
            rng.value(1.0)
        } else {
            0.5 + rng.unit()
        };
        let jitter = rng.vec3(0.3);
        let at = if rng.1 && rng.below(12) == 0 {
            rng.vec3(3.0)
        } else {
            [3.0 * k as f64 + jitter[0], jitter[1], jitter[2]]
        };
        pos.push(T::v3_from(at));
        radius.push(T::from_f64(r));
    }
    let mut vel: Vec<T::V3> = (0..n).map(|_| T::v3_from(rng.vec3(0.1))).collect();
    let mut omega: Vec<T::V3> = (0..n).map(|_| T::v3_from(rng.vec3(0.1))).collect();
    let density: Vec<T> = (0..n).map(|_| T::from_f64(rng.value(4.5))).collect();
    let mut time = T::from_f64(if rng.1 && rng.below(8) == 0 {
        rng.value(1.0)
    } else {
        rng.unit()
    });
    let nb = rng.below(n as u64 + 2) as usize;
    let bonds: Vec<Bond<T>> = (0..nb)
        .map(|k| {
            let (i, j) = if rng.1 && rng.below(10) == 0 {
                (
                    rng.below(n as u64 + 2) as usize,
                    rng.below(n as u64 + 2) as usize,
                )
            } else {
                (k % n, (k + 1) % n)
            };
            let length = if rng.1 && rng.below(8) == 0 {
                rng.value(3.0)
            } else if rng.below(16) == 0 {
                // Rest length zero: a spring's (Springs, FENE) or a refused bond.
                0.0
            } else {
                // The current distance, so that a clean case starts on its constraints.
                let d = sub(f64s::<T>(pos[i % n]), f64s::<T>(pos[j % n]));
                norm(d).max(1e-3)
            };
            Bond {
                i,
                j,
                length: T::from_f64(length),
            }
        })
        .collect();
    let mut p = Params::<T>::new(T::from_f64(if rng.1 && rng.below(8) == 0 {
        rng.value(0.01)
    } else {
        0.001 + 0.05 * rng.unit()
    }));
    p.method = METHODS[rng.below(5) as usize];
    p.solver.kind = SOLVERS[rng.below(4) as usize];
    p.hydro = HYDRO[rng.below(3) as usize];
    p.rotation = rng.below(2) == 0;
    p.allow_overlap = rng.below(2) == 0;
    p.stability_guard = rng.below(2) == 0;
    p.solver.max_iterations = 1 + rng.below(60) as u32;
    if rng.1 && rng.below(6) == 0 {
        p.solver.tolerance = T::from_f64(rng.value(1e-6));
    }
    if rng.below(10) == 0 {
        p.viscosity = T::from_f64(rng.value(1.0));
    }
    if rng.below(10) == 0 {
        p.gravity = T::v3_from(rng.vec3(1.0));
    }
    if rng.below(10) == 0 {
        p.vorticity = T::v3_from(rng.vec3(0.5));
    }
    if rng.below(10) == 0 {
        p.spring_stiffness = T::from_f64(rng.value(1e3));
    }
    // A clean case takes only the tables its method supports (so that it mostly steps);
    // a hostile one takes any.
    let hostile = rng.1;
    let fits = |ok: bool| hostile || ok;
    let overdamped = matches!(p.method, Method::Overdamped | Method::Overdamped2);
    let free_ok = fits(matches!(p.method, Method::Overdamped | Method::Springs));
    let noise_ok = fits(matches!(
        p.method,
        Method::Overdamped | Method::Springs | Method::RattleStable
    ));
    let one_sided_ok = fits(overdamped);
    // Hard contacts on a quarter of the cases: any capacity (zero included, and past
    // `DENSE_BONDS_MAX` rows), any rounds.
    if one_sided_ok && rng.below(4) == 0 {
        p.contacts = Some(Contacts {
            capacity: rng.below(2 * n as u64 + 40) as usize,
            max_rounds: rng.below(20) as u32,
        });
    }
    // A wall on a quarter: below the chain, or anywhere (a sphere under it is refused).
    if one_sided_ok && rng.below(4) == 0 {
        let height = if rng.below(4) == 0 {
            rng.value(-2.0)
        } else {
            -2.0 - rng.unit()
        };
        p.wall = Some(Wall::new(T::from_f64(height)));
    }
    // A periodic box on an eighth: edges around the chain's extent (so that it may wrap
    // and meet its own images), or hostile ones; a clean case drops what a box
    // refuses (a wall, the Oseen level) and keeps rotation.
    if rng.below(8) == 0 {
        let mut edge = |typical: f64| match rng.1 && rng.below(4) == 0 {
            true => rng.value(typical),
            false => typical * (0.5 + rng.unit()),
        };
        let size = [edge(3.0 * n as f64 + 6.0), edge(12.0), edge(12.0)];
        if let Ok(c) = Periodic::new(size.map(T::from_f64)) {
            p.periodic = Some(c);
            if !hostile {
                p.wall = None;
                if p.hydro == Hydro::Oseen {
                    p.hydro = Hydro::Rpy;
                }
            }
        }
        // Summed by PSE on half of the boxes: a usual tolerance, one below f32's floor,
        // or a hostile one (refused, typed: out of range, a sphere of a third of the
        // edge, a grid past its bounds).
        if rng.below(2) == 0 {
            p.pse = Some(match rng.below(4) {
                0 => 1e-9,
                1 if hostile => rng.value(1e-4),
                _ => [1e-3, 1e-5][rng.below(2) as usize],
            });
        }
    }
    p.matrix_free = free_ok && rng.below(6) == 0;
    if p.pse.is_some() && !hostile {
        // PSE gives products only.
        p.matrix_free = true;
    }
    // FENE springs on a sixth: a limit beyond the bonds, or a hostile one.
    if rng.below(6) == 0 {
        p.fene = Some(T::from_f64(rng.value(6.0)));
    }
    // Thermal noise on a quarter, drawn by either square root (or the default's pick).
    let one_sided = p.contacts.is_some() || p.wall.is_some();
    if noise_ok && fits(!one_sided) && rng.below(4) == 0 {
        let mut b = Brownian::new(T::from_f64(rng.value(0.05)));
        if rng.below(2) == 0 {
            b.drift = Drift::Uncorrected;
        }
        p.brownian = Some(b);
        p.noise_sqrt = NOISE_SQRT[rng.below(3) as usize];
        if !hostile && p.method == Method::RattleStable {
            p.noise_sqrt = NoiseSqrt::Cholesky;
        }
        if !hostile && p.matrix_free {
            p.noise_sqrt = NoiseSqrt::Lanczos;
        }
        if rng.1 && rng.below(4) == 0 {
            p.lanczos.max_iterations = rng.below(4) as u32;
            p.lanczos.tolerance = T::from_f64(rng.value(1e-6));
        }
    }
    // Storage: usually what the step needs, sometimes too little.
    let (ln, lb) = match (rng.1, rng.below(16)) {
        (true, 0) => (n.saturating_sub(1), nb),
        (true, 1) => (n, nb.saturating_sub(1)),
        _ => (n, nb),
    };
    let mut store = Buffers::<T>::new(Layout::for_params(&p, ln, lb));
    let mut arrays = pse_arrays(&p, &radius);
    let on_pse = arrays.is_some();
    let ws = store.workspace();
    #[cfg(feature = "pse")]
    let ws = match arrays.as_mut() {
        Some(a) => a.attach(ws),
        None => ws,
    };
    let mut ws = ws;
    // Sometimes a slice of the wrong length.
    let short = rng.below(40) == 0 && n > 1;
    let mut noise = Noise::new(rng.next());
    let noise0 = noise.save();
    let (pos0, vel0, omega0, time0) = (
        bits::<T>(&pos),
        bits::<T>(&vel),
        bits::<T>(&omega),
        time.to_f64().to_bits(),
    );
    let state = State {
        pos: &mut pos,
        vel: if short { &mut vel[..n - 1] } else { &mut vel },
        omega: &mut omega,
        radius: &radius,
        density: &density,
        time: &mut time,
        noise: Some(&mut noise),
    };
    let result = step_slices(state, &bonds, &p, &mut ws, &mut NoForce);
    let accepted = result.is_ok();
    match result {
        Err(e) => {
            let same = bits::<T>(&pos) == pos0
                && bits::<T>(&vel) == vel0
                && bits::<T>(&omega) == omega0
                && time.to_f64().to_bits() == time0
                && noise.save() == noise0;
            if !same {
                return Err(format!("refused ({e}) but changed the state"));
            }
        }
        Ok(_) => {
            let finite = pos
                .iter()
                .chain(&vel)
                .chain(&omega)
                .all(|&v| f64s::<T>(v).iter().all(|x| x.is_finite()));
            if !finite {
                return Err("accepted with a non-finite state".into());
            }
            if time.to_f64().partial_cmp(&f64::from_bits(time0))
                != Some(std::cmp::Ordering::Greater)
            {
                return Err(format!(
                    "accepted without advancing time ({} -> {})",
                    f64::from_bits(time0),
                    time.to_f64()
                ));
            }
        }
    }
    Ok((accepted, on_pse))
}

fn fuzz<T: Real>(salt: u64) {
    let (cases, seed) = settings(0x5EED_0011);
    let seed = seed ^ salt;
    let mut failures = Vec::new();
    let (mut accepted, mut on_pse) = (0u64, 0u64);
    for k in 0..cases {
        let mut rng = Draw(Rng::case(seed, k), false);
        // Half the cases clean (they should mostly step), half hostile.
        rng.1 = rng.below(2) == 0;
        let outcome =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| case::<T>(&mut rng)));
        match outcome {
            Ok(Ok((stepped, pse))) => {
                accepted += u64::from(stepped);
                on_pse += u64::from(stepped && pse);
            }
            Ok(Err(m)) => failures.push(format!("case {k}: {m}")),
            Err(_) => failures.push(format!("case {k}: panicked")),
        }
    }
    // The default run must step on PSE too (a short `FUZZ_CASES` run may not).
    if cfg!(feature = "pse") && cases >= 10_000 && on_pse == 0 {
        failures.push("no accepted step on PSE".into());
    }
    eprintln!("fuzz_step: {on_pse} accepted steps on PSE");
    let name = format!("fuzz_step {}", core::any::type_name::<T>());
    report(&name, cases, seed, accepted, &failures);
}

#[test]
fn step_survives_hostile_inputs_f64() {
    fuzz::<f64>(0);
}

#[test]
fn step_survives_hostile_inputs_f32() {
    fuzz::<f32>(1);
}
