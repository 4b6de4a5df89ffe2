//! Block products (several vectors in one pass over the mobility): each of the
//! `K` outputs holds the bits the single-vector product gives it, for the stored `f64`
//! blocks, the compact `f32` copy and the recompute path, with one band and with
//! sixteen, on one thread and on a pool.

use hydrorattle::glam::{DMat3, DVec3};
use hydrorattle::linalg::Sym;
use hydrorattle::noise::reduced;
use hydrorattle::parallel::{self, Parallel, Serial, band_scratch};
use hydrorattle::{Hydro, Real};
use hydrorattle_parallel::Threads;

/// `n` beads of radius 0.8 .. 1.2 on a helix (radius 3, rise 2.5 per bead).
fn helix(n: usize) -> (Vec<DVec3>, Vec<f64>) {
    let phi = 2.0 * ((9.0f64 - 6.25).sqrt() / 6.0).asin();
    let pos = (0..n)
        .map(|k| {
            let a = phi * k as f64;
            DVec3::new(3.0 * a.cos(), 3.0 * a.sin(), 2.5 * k as f64)
        })
        .collect();
    let radius = (0..n)
        .map(|i| 0.8 + 0.4 * ((i * 7) % 5) as f64 / 4.0)
        .collect();
    (pos, radius)
}

/// Vector `q` of a set of distinct right-hand sides.
fn rhs(n: usize, q: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| {
            let s = (i * (q + 3)) as f64;
            DVec3::new((0.7 * s).sin(), (0.3 * s + q as f64).cos(), 0.5 - q as f64)
        })
        .collect()
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
}

/// A single product `(par, x, y, z)`.
type Single<'a> = &'a dyn Fn(&dyn Parallel, &[DVec3], &mut [DVec3], &mut [DVec3]);

/// A block product of `K` vectors `(par, x, y, z)`.
type Block<'a, const K: usize> =
    &'a dyn Fn(&dyn Parallel, [&[DVec3]; K], [&mut [DVec3]; K], &mut [DVec3]);

/// The `K` products by `block` against `K` single products by `single`, on `par`.
fn check<const K: usize>(
    n: usize,
    par: &dyn Parallel,
    what: &str,
    single: Single,
    block: Block<K>,
) {
    let xs: Vec<Vec<DVec3>> = (0..K).map(|q| rhs(n, q)).collect();
    let mut z = vec![DVec3::ZERO; K * band_scratch(n)];
    let mut ys = vec![vec![DVec3::NAN; n]; K];
    let x: [&[DVec3]; K] = core::array::from_fn(|q| &xs[q][..]);
    {
        let mut it = ys.iter_mut();
        let y: [&mut [DVec3]; K] = core::array::from_fn(|_| &mut it.next().unwrap()[..]);
        block(par, x, y, &mut z);
    }
    for q in 0..K {
        let mut one = vec![DVec3::NAN; n];
        single(&Serial, &xs[q], &mut one, &mut z);
        assert_eq!(
            bits(&ys[q]),
            bits(&one),
            "{what}: N = {n}, K = {K}, vector {q}"
        );
    }
}

fn all_paths<const K: usize>(n: usize, par: &dyn Parallel) {
    let (pos, radius) = helix(n);
    let mut mu = vec![f64::M3_ZERO; n * (n + 1) / 2];
    parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
    check::<K>(
        n,
        par,
        "stored",
        &|p, x, y, z| parallel::product::<f64>(p, &mu, n, x, y, z),
        &|p, x, y, z| parallel::products::<f64, K>(p, &mu, n, x, y, z),
    );
    // The same mobility stored as symmetric blocks (six entries, as free-space steps
    // store it): each vector gets the nine-entry product's bits.
    let mut sym: Vec<Sym<f64>> = vec![[0.0; 6]; n * (n + 1) / 2];
    parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut sym).unwrap();
    check::<K>(
        n,
        par,
        "stored, symmetric blocks",
        &|p, x, y, z| parallel::product::<f64>(p, &mu, n, x, y, z),
        &|p, x, y, z| parallel::products::<f64, K>(p, &sym, n, x, y, z),
    );
    let (pos, radius) = (&pos[..], &radius[..]);
    check::<K>(
        n,
        par,
        "recompute",
        &|p, x, y, z| {
            parallel::free_product::<f64>(p, Hydro::Rpy, 1.0, pos, radius, x, y, z).unwrap()
        },
        &|p, x, y, z| {
            parallel::free_products::<f64, K>(p, Hydro::Rpy, 1.0, pos, radius, x, y, z).unwrap()
        },
    );
    let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
    let (x, mut y, mut z) = (
        rhs(n, 0),
        vec![DVec3::ZERO; n],
        vec![DVec3::ZERO; band_scratch(n)],
    );
    reduced::copy_apply::<f64>(&Serial, &mu, n, &mut copy, &x, &mut y, &mut z);
    // Packed from the symmetric blocks: the same copy, bit for bit.
    let mut from_sym = vec![f64::M3_ZERO; reduced::slots(n)];
    reduced::copy_apply::<f64>(&Serial, &sym, n, &mut from_sym, &x, &mut y, &mut z);
    let entries = |c: &[DMat3]| -> Vec<u64> {
        c.iter()
            .flat_map(|m| m.to_cols_array().map(f64::to_bits))
            .collect()
    };
    assert_eq!(
        entries(&from_sym),
        entries(&copy),
        "copy from symmetric blocks"
    );
    check::<K>(
        n,
        par,
        "compact",
        &|p, x, y, z| reduced::apply::<f64>(p, &copy, n, x, y, z),
        &|p, x, y, z| reduced::apply_k::<f64, K>(p, &copy, n, x, y, z),
    );
}

#[test]
fn block_products_give_each_vector_the_bits_of_its_own_product() {
    let pool = Threads::new(3).unwrap();
    // One band (below `BANDED_MIN`) and sixteen; the compact copy needs no band count.
    for n in [37, 530] {
        all_paths::<2>(n, &Serial);
        all_paths::<3>(n, &pool);
    }
    all_paths::<4>(530, &pool);
    all_paths::<1>(530, &Serial);
}

/// A nested pair: the block recompute path gives the single product's error.
#[test]
fn block_recompute_refuses_nested_spheres_as_the_single_product_does() {
    let n = 600;
    let (mut pos, radius) = helix(n);
    pos[550] = pos[20];
    let (x, mut y, mut z) = (
        rhs(n, 0),
        [vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]],
        vec![DVec3::ZERO; 2 * band_scratch(n)],
    );
    let one = parallel::free_product::<f64>(
        &Serial,
        Hydro::Rpy,
        1.0,
        &pos,
        &radius,
        &x,
        &mut y[0].clone(),
        &mut z,
    );
    let [y0, y1] = &mut y;
    let two = parallel::free_products::<f64, 2>(
        &Serial,
        Hydro::Rpy,
        1.0,
        &pos,
        &radius,
        [&x, &x],
        [y0, y1],
        &mut z,
    );
    assert!(one.is_err());
    assert_eq!(two, one);
}

/// The runtime-selected AVX2 copies (`wide`) against the portable kernel functions,
/// bit for bit (on a CPU without AVX2 both are the portable code).
#[test]
fn the_avx2_copies_give_the_portable_bits() {
    use hydrorattle_parallel::wide;
    eprintln!("AVX2 copies in use: {}", wide::avx2());
    let pool = Threads::new(2).unwrap();
    for n in [37, 530] {
        let (pos, radius) = helix(n);
        let mut mu = vec![f64::M3_ZERO; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut mu).unwrap();
        let mut sym: Vec<Sym<f64>> = vec![[0.0; 6]; n * (n + 1) / 2];
        parallel::assemble::<f64>(&Serial, Hydro::Rpy, 1.0, &pos, &radius, &mut sym).unwrap();
        let (pos, radius, mu) = (&pos[..], &radius[..], &mu[..]);
        check::<2>(
            n,
            &pool,
            "stored, AVX2",
            &|p, x, y, z| parallel::product::<f64>(p, mu, n, x, y, z),
            &|p, x, y, z| wide::products::<2>(p, mu, n, x, y, z),
        );
        check::<2>(
            n,
            &pool,
            "stored, symmetric blocks, AVX2",
            &|p, x, y, z| parallel::product::<f64>(p, mu, n, x, y, z),
            &|p, x, y, z| wide::products::<2>(p, &sym, n, x, y, z),
        );
        check::<1>(
            n,
            &pool,
            "recompute, AVX2",
            &|p, x, y, z| {
                parallel::free_product::<f64>(p, Hydro::Rpy, 1.0, pos, radius, x, y, z).unwrap()
            },
            &|p, x, y, z| {
                wide::free_products::<1>(p, Hydro::Rpy, 1.0, pos, radius, x, y, z).unwrap()
            },
        );
        let mut copy = vec![f64::M3_ZERO; reduced::slots(n)];
        let (x, mut y) = (rhs(n, 0), vec![DVec3::ZERO; n]);
        let mut z = vec![DVec3::ZERO; band_scratch(n)];
        reduced::copy_apply::<f64>(&Serial, mu, n, &mut copy, &x, &mut y, &mut z);
        check::<2>(
            n,
            &pool,
            "compact, AVX2",
            &|p, x, y, z| reduced::apply::<f64>(p, &copy, n, x, y, z),
            &|p, x, y, z| wide::compact_products::<2>(p, &copy, n, x, y, z),
        );
    }
}
