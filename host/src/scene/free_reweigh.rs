//! Free space's `auto` over a whole run: the fast product weighed against the pair sums
//! before every step, on the cloud as it is (`[free_space] reweigh`).
//!
//! The cost model ([`free_cost`](super::free_cost)) prices the fast product from the
//! spheres' bounding box, as if they filled it evenly. That holds for the cloud a run
//! starts from, and fails for one that leaves a tail: the tail stretches the box, the
//! fast product's spreading width grows with the box's mean spacing, and the pairs
//! within its cutoff in the dense core grow with the box's volume (a falling cloud of
//! 10^4 spheres, 100 times as tall after 180 time units, runs its fast product 11 times
//! slower than the pair sums). The pair sums' cost depends on the number of spheres
//! alone. So before each step a run that reweighs **counts** the pairs within the
//! fast product's cutoff ([`count_pairs`], on a cell list, stopping at the count where the
//! two paths tie) and takes the pair sums where the fast product's modelled time, with
//! that count, passes theirs.
//!
//! The model's near-pair constant was fitted against counted pairs
//! (`examples/free_cost.rs` counts them), so the count enters it as it is, as it does
//! in `auto`'s first choice ([`choose_for`](super::free_cost::choose_for)); the even
//! estimate undercounts a ball's pairs (a ball fills `pi / 6` of its box). Measured
//! frame by frame on a falling cloud (`study/examples/reweigh_frames.rs`), a step's
//! time grows by the fitted constant per counted pair. Past [`SAMPLED`] spheres the
//! count is estimated from a fixed sample of them (a few per cent off, a few
//! milliseconds a step).
//!
//! Where the kernel refuses the pair sums' step (a Brownian step whose Lanczos run
//! passes its cap: the model's iterations read the box, which a tail stretches while
//! the dense core needs as many as before), the step is taken on the fast product, from
//! the same state and the same generator: the bits of a system on the fast product
//! alone.
//!
//! The choice is a function of the positions alone: the same bits on any number of
//! threads, and a run resumed from a checkpoint chooses as the uninterrupted run did.

use std::collections::HashMap;

use hydrorattle::{Params, Real};

use super::free_cost::{FreeChoice, FreeCost, Spheres, fast_params, step_cost, within_cap};
use super::sizing::Plan;
use super::{Contact, Precision, Thermal};

/// Spheres whose neighbours [`count_pairs`] counts one by one at most; past them it
/// counts those of every `ceil(N / SAMPLED)`-th sphere (by index) and scales the sum:
/// a few per cent off the whole count on a cloud, for a few milliseconds a step at
/// 10^5 spheres (a cost model needs no more).
pub const SAMPLED: usize = 2048;

/// Pairs of `pos` closer than `r_cut`, on a cell list of cells `r_cut` wide: exactly up
/// to [`SAMPLED`] spheres, else estimated from the neighbours of every
/// `ceil(N / SAMPLED)`-th sphere; counted up to `cap` (a count at `cap` means at least
/// `cap`). Neither depends on the order of the cells visited.
pub fn count_pairs(pos: &[[f64; 3]], r_cut: f64, cap: u64) -> u64 {
    let n = pos.len();
    if !(r_cut > 0.0 && r_cut.is_finite()) || n < 2 || cap == 0 {
        return 0;
    }
    // Far cells saturate and wrap: that only adds candidates, checked by distance.
    let cell = |p: &[f64; 3]| p.map(|x| (x / r_cut).floor() as i64);
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in pos.iter().enumerate() {
        cells.entry(cell(p)).or_default().push(i);
    }
    let stride = n.div_ceil(SAMPLED);
    let samples = n.div_ceil(stride);
    // Each pair is met from both ends; sampled, each sphere stands for `stride`.
    let per_neighbour = n as f64 / (2.0 * samples as f64);
    let r2 = r_cut * r_cut;
    let mut met = 0u64;
    for (i, p) in pos.iter().enumerate().step_by(stride) {
        let c = cell(p);
        for d in 0..27 {
            let k = [-1, 0, 1];
            let k = [
                c[0].wrapping_add(k[d / 9]),
                c[1].wrapping_add(k[(d / 3) % 3]),
                c[2].wrapping_add(k[d % 3]),
            ];
            let Some(js) = cells.get(&k) else { continue };
            for &j in js.iter().filter(|&&j| j != i) {
                let q = pos[j];
                let r = (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>();
                met += u64::from(r < r2);
            }
        }
        if met as f64 * per_neighbour >= cap as f64 {
            return cap;
        }
    }
    // Exact where every sphere was visited (`met` is then even).
    match stride {
        1 => met / 2,
        _ => (met as f64 * per_neighbour).round() as u64,
    }
    .min(cap)
}

/// The cost model's plan of a fast free-space step with parameters `p`.
fn plan_of<T: Real>(p: &Params<T>) -> Plan {
    let mut plan = Plan::free(p.method, p.solver.kind);
    plan.rotation = p.rotation;
    plan.precision = match core::mem::size_of::<T>() {
        4 => Precision::F32,
        _ => Precision::F64,
    };
    plan.contact = p.contacts.map(|c| Contact::Hard {
        capacity: Some(c.capacity),
    });
    plan.brownian = p.brownian.map(|b| Thermal {
        temperature: b.temperature.to_f64(),
        seed: 0,
        drift: b.drift,
        sqrt: p.noise_sqrt,
    });
    plan.matrix_free = true;
    plan.fast = true;
    plan
}

/// The positions as `f64` and their largest radius.
fn widened<T: Real>(pos: &[T::V3], radius: &[T]) -> (Vec<[f64; 3]>, f64) {
    let a_max = radius.iter().fold(0.0f64, |m, a| m.max(a.to_f64()));
    (pos.iter().map(|&p| T::v3_to_f64(p)).collect(), a_max)
}

/// The weighing a run makes before each step (module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Reweigh {
    plan: Plan,
    bonds: usize,
    tolerance: f64,
}

impl Reweigh {
    /// The weighing for steps with parameters `p` (the fast product's: [`Params::pse`]
    /// in free space) with `bonds` constraint rows; `None` where the step does not take
    /// the fast product, or takes it as the near field's far field (weighed by neither
    /// path).
    pub fn new<T: Real>(p: &Params<T>, bonds: usize) -> Option<Self> {
        let place = p.place();
        let free = place.cell().is_none() && place.surfaces().is_empty();
        let takes = free && p.near.is_none() && p.hydro == hydrorattle::Hydro::Rpy;
        let tolerance = p.pse.filter(|_| takes)?;
        Some(Reweigh {
            plan: plan_of(p),
            bonds,
            tolerance,
        })
    }

    /// The path for a step from the spheres at `pos` with radii `radius`: the pair sums
    /// ([`FreeChoice::MatrixFree`]) where the fast product's modelled time with the
    /// pairs counted now passes theirs (and their noise stays within the Lanczos cap),
    /// else [`FreeChoice::Fast`].
    pub fn choose<T: Real>(&self, pos: &[T::V3], radius: &[T]) -> FreeChoice {
        let (pos, a_max) = widened::<T>(pos, radius);
        let w = match self.weights(&pos, a_max) {
            Weights::Sums => return FreeChoice::MatrixFree,
            Weights::Fast => return FreeChoice::Fast,
            Weights::Linear(w) => w,
        };
        if w.t0 >= w.sums {
            return FreeChoice::MatrixFree;
        }
        // The pairs at the tie: a count that reaches them needs go no further.
        let tie = (w.sums - w.t0) / w.slope;
        let cap = tie.max(0.0).ceil();
        let cap = if cap >= u64::MAX as f64 {
            u64::MAX
        } else {
            cap as u64
        };
        match count_pairs(&pos, w.r_cut, cap) >= cap {
            true => FreeChoice::MatrixFree,
            false => FreeChoice::Fast,
        }
    }

    /// The modelled seconds of a step from the spheres at `pos` (radii `radius`) on
    /// the fast product, with every pair within its cutoff counted, and on the pair
    /// sums: what [`Reweigh::choose`] compares (it stops counting at the tie). `None`
    /// where one of the two is not weighed (the kernel refuses the fast parameters, or
    /// the pair sums cannot run the step).
    pub fn modelled<T: Real>(&self, pos: &[T::V3], radius: &[T]) -> Option<[f64; 2]> {
        let (pos, a_max) = widened::<T>(pos, radius);
        let Weights::Linear(w) = self.weights(&pos, a_max) else {
            return None;
        };
        let pairs = count_pairs(&pos, w.r_cut, u64::MAX) as f64;
        Some([w.t0 + w.slope * pairs, w.sums])
    }

    /// The step's modelled times as functions of the fast product's near pairs.
    fn weights(&self, pos: &[[f64; 3]], a_max: f64) -> Weights {
        let s = Spheres::at(pos, a_max, self.bonds, true);
        let plan = &self.plan;
        let even = FreeCost::of(&s, self.tolerance);
        let Some(sums) = step_cost(plan, &s, &even, FreeChoice::MatrixFree)
            .filter(|_| within_cap(plan, &s, FreeChoice::MatrixFree))
        else {
            return Weights::Fast;
        };
        // The fast step's time is linear in the modelled pairs: its value at none and
        // its slope give the tie.
        let fast = |x: f64| {
            let c = FreeCost::counted(&s, self.tolerance, &|_| x);
            step_cost(plan, &s, &c, FreeChoice::Fast)
        };
        match (
            fast(0.0),
            fast(1e6),
            fast_params(&s, self.tolerance, plan.rotation),
        ) {
            (Some(t0), Some(t1), Some(ff)) if t1 > t0 => Weights::Linear(Linear {
                sums,
                t0,
                slope: (t1 - t0) / 1e6,
                r_cut: ff.r_cut(),
            }),
            // The kernel refuses the fast parameters here: the pair sums run.
            _ => Weights::Sums,
        }
    }
}

/// What a step weighs ([`Reweigh::choose`]).
enum Weights {
    /// The pair sums, whatever the count (the fast product cannot run).
    Sums,
    /// The fast product, whatever the count (the pair sums cannot run).
    Fast,
    /// The fast product's time linear in its near pairs against the pair sums'.
    Linear(Linear),
}

/// A step's modelled seconds: the pair sums', and the fast product's `t0 + slope
/// pairs` with its cutoff `r_cut`.
struct Linear {
    sums: f64,
    t0: f64,
    slope: f64,
    r_cut: f64,
}
