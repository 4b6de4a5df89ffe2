//! The acceptance's overlap check in bands over the kernel's cell list
//! (`hydrorattle::cell_list`, from `CELLS_MIN` spheres on) reports the pair a single
//! pass over every pair in the order `(i, j)`, `i < j`, meets first, on any thread
//! count; and a settling suspension with hard contacts gives the same bits on any
//! thread count.

use hydrorattle::parallel::{Parallel, Serial, bands};
use hydrorattle::{
    Contacts, Hydro, Layout, NoForce, Params, Real, StepError, StepReport, cell_list, step_slices,
};
use hydrorattle_heap::{Buffers, Spheres};
use hydrorattle_parallel::Threads;

const N: usize = 600;

/// `N` unit spheres on a lattice of spacing 3 (10 x 10 x 6), with `moves` (sphere,
/// onto sphere) placing a sphere 1.5 from another's centre.
fn lattice(moves: &[(usize, usize)]) -> Vec<[f64; 3]> {
    let mut pos: Vec<[f64; 3]> = (0..N)
        .map(|k| [(k % 10) as f64, ((k / 10) % 10) as f64, (k / 100) as f64].map(|x| 3.0 * x))
        .collect();
    for &(m, to) in moves {
        pos[m] = [pos[to][0], pos[to][1] + 1.5, pos[to][2]];
    }
    pos
}

/// The first overlapping pair in the order `(i, j)`, `i < j`, by brute force.
fn first(pos: &[[f64; 3]]) -> Option<(usize, usize)> {
    let d2 = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>();
    (0..N)
        .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
        .find(|&(i, j)| d2(pos[i], pos[j]) < 4.0)
}

/// `steps` free-draining steps from `start` (with contacts if asked), on `par`: every
/// report, or the error, and the end positions' bits.
fn run<T: Real>(
    start: &[[f64; 3]],
    contacts: bool,
    steps: usize,
    par: &dyn Parallel,
) -> (Result<Vec<StepReport<T>>, StepError>, Vec<u64>) {
    let mut p = Params::<T>::new(T::from_f64(0.5));
    p.hydro = Hydro::FreeDraining;
    p.contacts = contacts.then(|| Contacts::new(2 * N));
    let pos: Vec<T::V3> = start.iter().map(|&x| T::v3_from(x)).collect();
    let radius = vec![T::ONE; N];
    // With contacts, heavier spheres in every third layer: they catch up with the ones
    // below. Without, all alike: they move together and keep their distances.
    let density: Vec<T> = (0..N)
        .map(|k| {
            T::from_f64(if contacts && (k / 100) % 3 == 2 {
                12.0
            } else {
                2.0
            })
        })
        .collect();
    let mut s = Spheres::at_rest(pos, radius, density);
    let mut store = Buffers::<T>::new(Layout::for_params(&p, N, 0));
    let mut ws = store.workspace().with_parallel(par);
    let reports = (0..steps)
        .map(|_| step_slices(s.state(), &[], &p, &mut ws, &mut NoForce))
        .collect();
    let bits = s
        .pos
        .iter()
        .flat_map(|&v| T::xyz(v).map(|c| c.to_f64().to_bits()))
        .collect();
    (reports, bits)
}

fn pools() -> Vec<Threads> {
    [1, 2, 3, 4].map(|t| Threads::new(t).unwrap()).into()
}

#[test]
fn the_banded_check_reports_the_first_pair_on_any_thread_count() {
    const { assert!(N >= cell_list::CELLS_MIN) };
    assert!(bands(N) > 1);
    let cases: [&[(usize, usize)]; 4] = [
        &[(300, 200)],
        &[(300, 200), (590, 10)],
        &[(590, 10), (599, 12)],
        &[(599, 11), (598, 10), (40, 30)],
    ];
    for moves in cases {
        let start = lattice(moves);
        let (i, j) = first(&start).unwrap();
        let want = Err(StepError::Overlap { i, j });
        let (serial, _) = run::<f64>(&start, false, 1, &Serial);
        assert_eq!(serial, want, "{moves:?}");
        for pool in pools() {
            let (r, _) = run::<f64>(&start, false, 1, &pool);
            assert_eq!(r, want, "{moves:?} on {} threads", pool.threads());
        }
    }
}

fn contacts_agree<T: Real>() {
    let start = lattice(&[]);
    let (serial, bits) = run::<T>(&start, true, 6, &Serial);
    let serial = serial.unwrap();
    let most = serial.iter().map(|r| r.contacts).max().unwrap();
    assert!(most >= 50, "{most} contacts: the test needs some");
    for pool in pools() {
        let (r, b) = run::<T>(&start, true, 6, &pool);
        assert_eq!(r.unwrap(), serial, "{} threads", pool.threads());
        assert!(b == bits, "{} threads: different bits", pool.threads());
    }
}

#[test]
fn contact_steps_are_the_same_bits_on_any_thread_count_f64() {
    contacts_agree::<f64>();
}

#[test]
fn contact_steps_are_the_same_bits_on_any_thread_count_f32() {
    contacts_agree::<f32>();
}
