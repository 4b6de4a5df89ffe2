//! The mobility's bands on a thread pool give the bits of one thread (the bands and
//! every sum's order depend on the bead count alone), and the banded product is the
//! one-pass product up to rounding. Thermal steps with the Lanczos noise
//! too give the same bits on any thread count.

use hydrorattle::glam::DVec3;
use hydrorattle::parallel::{self, BANDED_MIN, Parallel, Serial, band_scratch, bands};
use hydrorattle::{
    Bond, Brownian, Hydro, Layout, Method, NoForce, Noise, NoiseSqrt, Params, Real, linalg,
    mobility, step_slices,
};
use hydrorattle_heap::{Buffers, Spheres};
use hydrorattle_parallel::Threads;

/// `n` beads of radius 1 on a helix (radius 3, rise 2.5 per bead), bonds of length 3.
fn helix(n: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
    let (rise, r) = (2.5f64, 3.0f64);
    let phi = 2.0 * ((9.0 - rise * rise).sqrt() / (2.0 * r)).asin();
    let pos = (0..n)
        .map(|k| {
            let a = phi * k as f64;
            [r * a.cos(), r * a.sin(), rise * k as f64]
        })
        .collect();
    (pos, vec![1.0; n])
}

fn pools() -> Vec<Threads> {
    [1, 2, 3, 4].map(|t| Threads::new(t).unwrap()).into()
}

#[test]
fn products_and_assembly_are_the_same_bits_on_any_thread_count() {
    let n = BANDED_MIN + 188;
    assert!(bands(n) > 1);
    let (p, radius) = helix(n);
    let pos: Vec<DVec3> = p.iter().map(|&x| DVec3::from(x)).collect();
    let tri = n * (n + 1) / 2;
    let mut mu = vec![f64::M3_ZERO; tri];
    mobility::assemble_tt(Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
    let x: Vec<DVec3> = (0..n)
        .map(|i| {
            DVec3::new(
                (i as f64).sin(),
                (0.3 * i as f64).cos(),
                1.0 / (1.0 + i as f64),
            )
        })
        .collect();
    let mut z = vec![DVec3::ZERO; band_scratch(n)];
    let mut serial = vec![DVec3::ZERO; n];
    parallel::product::<f64>(&Serial, &mu, n, &x, &mut serial, &mut z);
    // Against the one-pass product: equal to rounding (relative 1e-13 of the row scale).
    let mut plain = vec![DVec3::ZERO; n];
    linalg::sym_matvec::<f64>(&mu, n, &x, &mut plain);
    let scale = plain
        .iter()
        .map(|v| v.abs().max_element())
        .fold(0.0, f64::max);
    for (a, b) in serial.iter().zip(&plain) {
        assert!((*a - *b).abs().max_element() <= 1e-13 * scale, "{a} vs {b}");
    }
    for pool in pools() {
        let par: &dyn Parallel = &pool;
        let mut y = vec![DVec3::ZERO; n];
        parallel::product::<f64>(par, &mu, n, &x, &mut y, &mut z);
        assert_eq!(bits(&y), bits(&serial), "{} threads", pool.threads());
        // Assembly alone, and assembly fused with the product.
        let mut mu2 = vec![f64::M3_ZERO; tri];
        parallel::assemble::<f64>(par, Hydro::Rpy, 1.0, &pos, &radius, &mut mu2).unwrap();
        assert!(mu2 == mu, "{} threads: assembly", pool.threads());
        let (mut mu3, mut y3) = (vec![f64::M3_ZERO; tri], vec![DVec3::ZERO; n]);
        parallel::assemble_apply::<f64>(
            par,
            Hydro::Rpy,
            1.0,
            &pos,
            &radius,
            &mut mu3,
            &x,
            &mut y3,
            &mut z,
        )
        .unwrap();
        assert!(mu3 == mu, "{} threads: fused assembly", pool.threads());
        assert_eq!(
            bits(&y3),
            bits(&serial),
            "{} threads: fused",
            pool.threads()
        );
    }
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

/// Three overdamped steps of a settling helix (Krylov, one banded assembly and product
/// plus a banded product per iteration): the positions' bits, for a given executor.
fn steps<T: Real>(n: usize, par: &dyn Parallel) -> Vec<u64> {
    steps_at::<T>(n, par, None)
}

/// [`steps`], at temperature `kt` if given (Lanczos noise, midpoint drift: banded
/// products at the start, a banded assembly and product at the midpoint).
fn steps_at<T: Real>(n: usize, par: &dyn Parallel, kt: Option<f64>) -> Vec<u64> {
    let (p, radius) = helix(n);
    let pos: Vec<T::V3> = p.iter().map(|&x| T::v3_from(x)).collect();
    let radius: Vec<T> = radius.iter().map(|&a| T::from_f64(a)).collect();
    let bonds: Vec<Bond<T>> = (1..n)
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: T::norm(pos[i] - pos[i - 1]),
        })
        .collect();
    let mut params = Params::<T>::new(T::from_f64(0.05));
    assert_eq!(params.method, Method::Overdamped);
    params.brownian = kt.map(|t| Brownian::new(T::from_f64(t)));
    params.noise_sqrt = NoiseSqrt::Lanczos;
    let mut store = Buffers::<T>::new(Layout::for_params(&params, n, n - 1));
    let mut ws = store.workspace().with_parallel(par);
    let mut s = Spheres::at_rest(pos, radius, vec![T::from_f64(4.5); n]);
    s.noise = kt.map(|_| Noise::new(3));
    for _ in 0..3 {
        let r = step_slices(s.state(), &bonds, &params, &mut ws, &mut NoForce).unwrap();
        assert_eq!(r.noise_iterations > 0, kt.is_some());
    }
    s.pos
        .iter()
        .flat_map(|&v| T::xyz(v).map(|c| c.to_f64().to_bits()))
        .collect()
}

/// Counts the jobs it runs (on the calling thread).
#[derive(Debug, Default)]
struct Counting(std::sync::atomic::AtomicUsize);

impl Parallel for Counting {
    fn run(&self, jobs: &mut [&mut (dyn FnMut() + Send)]) {
        self.0
            .fetch_add(jobs.len(), std::sync::atomic::Ordering::Relaxed);
        Serial.run(jobs);
    }
}

fn steps_agree<T: Real>() {
    let n = BANDED_MIN + 88;
    let serial = steps::<T>(n, &Serial);
    // The steps did go through the executor, in bands.
    let counting = Counting::default();
    assert!(steps::<T>(n, &counting) == serial);
    let jobs = counting.0.into_inner();
    assert!(jobs >= 3 * 2 * bands(n), "{jobs} jobs in three steps");
    for pool in pools() {
        assert!(
            steps::<T>(n, &pool) == serial,
            "{} threads: different bits",
            pool.threads()
        );
    }
}

#[test]
fn overdamped_steps_are_the_same_bits_on_any_thread_count_f64() {
    steps_agree::<f64>();
}

#[test]
fn overdamped_steps_are_the_same_bits_on_any_thread_count_f32() {
    steps_agree::<f32>();
}

/// From `REDUCED_MIN` beads on (f64) the Lanczos products read the reduced copy in
/// `f32` lanes, written by the start's assembly band by band: the same bits on any
/// thread count too.
#[test]
fn brownian_reduced_copy_steps_are_the_same_bits_on_any_thread_count() {
    let n = hydrorattle::noise::reduced::REDUCED_MIN + 40;
    let serial = steps_at::<f64>(n, &Serial, Some(1.0));
    for pool in pools().into_iter().skip(1).take(1) {
        assert!(
            steps_at::<f64>(n, &pool, Some(1.0)) == serial,
            "{} threads: different bits through the reduced copy",
            pool.threads()
        );
    }
}

#[test]
fn brownian_lanczos_steps_are_the_same_bits_on_any_thread_count() {
    let n = BANDED_MIN + 88;
    let serial = steps_at::<f64>(n, &Serial, Some(1.0));
    assert!(serial != steps::<f64>(n, &Serial), "no noise");
    for pool in pools().into_iter().take(2) {
        assert!(
            steps_at::<f64>(n, &pool, Some(1.0)) == serial,
            "{} threads: different bits at temperature",
            pool.threads()
        );
    }
}
