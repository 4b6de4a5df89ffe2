//! One overdamped step (first and second order) of a folded 25-bead helix with and
//! without hard contacts (`contacts/...`), f64, contact and round counts printed.

use std::hint::black_box;

use criterion::{BatchSize, BenchmarkId, Criterion};
use hydrorattle::{
    BondSet, Layout, Method, NoForce, Params, Particle, ParticleSet, Real, SolverKind, step,
};
use hydrorattle_heap::Buffers;

/// A Figure 1 (b)-like helix: head of radius 2^(1/3) then 24 unit tails, bonds
/// 1.05 (a_i + a_j), helix radius 3, rise 0.5 per bead.
fn short_helix() -> Vec<([f64; 3], f64)> {
    let mut out: Vec<([f64; 3], f64)> = Vec::new();
    let mut phi = 0.0f64;
    for k in 0..25 {
        let a = if k == 0 { 2f64.cbrt() } else { 1.0 };
        if let Some(&(_, prev)) = out.last() {
            let d = 1.05 * (prev + a);
            phi += 2.0 * ((d * d - 0.25f64).sqrt() / 6.0).asin();
        }
        out.push(([3.0 * phi.cos(), 3.0 * phi.sin(), 0.5 * k as f64], a));
    }
    out
}

/// One step on the 25-bead helix of [`short_helix`] after 1000 steps of dt = 0.1 with
/// hard contacts (t = 100: folded, beads touching), f64: the first- and second-order
/// overdamped steps with and without contacts (`contacts/...`). Prints the contacts
/// held, the active-set rounds and the Newton iterations of the timed step: counts next
/// to times.
pub(crate) fn contact_benches(c: &mut Criterion) {
    const N: usize = 25;
    let mut ps = ParticleSet::<f64, N>::new();
    for (x, a) in short_helix() {
        ps.push(Particle::new(f64::v3_from(x), a, 4.5)).unwrap();
    }
    let bonds = BondSet::<f64, 24>::chain(&ps.pos).unwrap();
    let with = |method, contacts: bool| {
        let mut q = Params::<f64>::new(0.1);
        q.method = method;
        q.solver.kind = SolverKind::Newton;
        q.contacts = contacts.then(|| hydrorattle::Contacts::new(3 * N));
        // Without contacts spheres may overlap (else the step is refused).
        q.allow_overlap = !contacts;
        q
    };
    let settle = with(Method::Overdamped2, true);
    let mut store = Buffers::<f64>::new(Layout::for_params(&settle, N, 24));
    let (mut held, mut most, mut rounds) = (0u64, 0, 0u64);
    for _ in 0..1000 {
        let r = step(
            &mut ps,
            &bonds,
            &settle,
            &mut store.workspace(),
            &mut NoForce,
        )
        .unwrap();
        held += u64::from(r.contacts);
        most = most.max(r.contacts);
        rounds += u64::from(r.contact_rounds);
    }
    eprintln!(
        "contacts: settling 1000 steps: {:.2} contacts held per step (at most {most}), {:.2} active-set rounds per final projection",
        held as f64 / 1000.0,
        rounds as f64 / 1000.0
    );
    for (label, method, contacts) in [
        ("overdamped", Method::Overdamped, false),
        ("overdamped+contacts", Method::Overdamped, true),
        ("overdamped2", Method::Overdamped2, false),
        ("overdamped2+contacts", Method::Overdamped2, true),
    ] {
        let q = with(method, contacts);
        let mut store = Buffers::<f64>::new(Layout::for_params(&q, N, 24));
        let rep = step(
            &mut ps.clone(),
            &bonds,
            &q,
            &mut store.workspace(),
            &mut NoForce,
        );
        match rep {
            Ok(r) => eprintln!(
                "contacts/{label}: {} contacts held, {} active-set rounds, {} Newton iterations",
                r.contacts, r.contact_rounds, r.iterations
            ),
            Err(e) => {
                eprintln!("contacts/{label}: refused ({e}); not timed");
                continue;
            }
        }
        let mut g = c.benchmark_group(format!("contacts/{label}"));
        g.bench_function(BenchmarkId::from_parameter(N), |b| {
            b.iter_batched_ref(
                || ps.clone(),
                |s| {
                    let _ = black_box(step(s, &bonds, &q, &mut store.workspace(), &mut NoForce));
                },
                BatchSize::LargeInput,
            )
        });
        g.finish();
    }
}
