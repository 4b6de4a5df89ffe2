//! The fast free-space product's kernel transform kept in the caller's reals between
//! steps (`mobility::free_fast`, `geometry::free::fast`): a step whose parameters, derived
//! from the cloud's rounded bounding box, are those the transform was computed for keeps
//! it, and gives the bits of the same step on freshly zeroed arrays. Checked:
//!
//! * a falling cloud over several steps, arrays kept, against each step taken again
//!   from its start on zeroed arrays: the same bits, and the transform kept;
//! * a cloud moved as a whole keeps the transform (and the bits of fresh arrays); a
//!   cloud stretched past the rounding's step computes it again;
//! * arrays holding other content than a header written by the product compute it;
//! * the rounding of the edges: at least the edge, at most a sixteenth (or a radius)
//!   above it, the same within a step.
//!
//! `cargo test --release --test kernel fast_keep::`.

use hydrorattle::integrate::{fast_storage, step_slices};
use hydrorattle::mobility::free_fast::{FreeFast, TransformCounts, round_extent, transform_counts};
use hydrorattle::{Layout, Method, NoForce, Params, Real, State};
use hydrorattle_heap::{Buffers, FreeBuffers};

type V = <f64 as Real>::V3;

/// SplitMix64 in `[0, 1)`.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` unit spheres uniformly in a ball at volume fraction 0.05 (equal radii never
/// nest; overlaps allowed).
fn ball(n: usize) -> Vec<V> {
    let r = (n as f64 / 0.05).cbrt();
    let mut rng = Rng(n as u64);
    let mut pos = vec![];
    while pos.len() < n {
        let p = [0, 1, 2].map(|_| r * (2.0 * rng.next() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= r * r {
            pos.push(f64::v3_from(p));
        }
    }
    pos
}

/// A sedimenting cloud's step on the fast product at tolerance 1e-4: densities 1 to
/// 3, so that the cloud deforms as it falls.
fn params() -> Params<f64> {
    let mut p = Params::<f64>::new(0.5);
    p.method = Method::Overdamped;
    p.allow_overlap = true;
    p.matrix_free = true;
    p.pse = Some(1e-4);
    p
}

/// The fast product's arrays.
type Arrays = FreeBuffers<f64>;

/// The fast arrays, zeroed, sized for `pos`.
fn arrays(p: &Params<f64>, pos: &[V]) -> Arrays {
    arrays_for(p, &[pos])
}

/// The fast arrays, zeroed, large enough for each cloud of `clouds`.
fn arrays_for(p: &Params<f64>, clouds: &[&[V]]) -> Arrays {
    let mut a = Arrays::default();
    for pos in clouds {
        let z = fast_storage(p, pos, &vec![1.0; pos.len()])
            .unwrap()
            .unwrap();
        a.grow(z);
    }
    a
}

/// One step of `p` from `pos` over the arrays `a`: the positions after, as bits.
fn step_on(p: &Params<f64>, pos: &[V], a: &mut Arrays) -> Vec<u64> {
    let n = pos.len();
    let rad = vec![1.0; n];
    let density: Vec<f64> = (0..n).map(|i| 1.0 + (i % 3) as f64).collect();
    let mut buf = Buffers::<f64>::new(Layout::for_params(p, n, 0));
    let mut ws = a.attach(buf.workspace());
    let (mut pos, mut vel, mut omega) = (pos.to_vec(), vec![V::ZERO; n], vec![V::ZERO; n]);
    let mut time = 0.0;
    let state = State {
        pos: &mut pos,
        vel: &mut vel,
        omega: &mut omega,
        radius: &rad,
        density: &density,
        time: &mut time,
        noise: None,
    };
    step_slices(state, &[], p, &mut ws, &mut NoForce).unwrap();
    pos.iter()
        .flat_map(|r| f64::xyz(*r).map(f64::to_bits))
        .collect()
}

fn from_bits(b: &[u64]) -> Vec<V> {
    b.chunks(3)
        .map(|c| {
            f64::v3(
                f64::from_bits(c[0]),
                f64::from_bits(c[1]),
                f64::from_bits(c[2]),
            )
        })
        .collect()
}

fn counts(a: &Arrays) -> TransformCounts {
    transform_counts(&a.reals).expect("a transform held")
}

#[test]
fn kept_transform_gives_the_bits_of_fresh_arrays_as_a_cloud_falls() {
    let p = params();
    let mut pos = ball(400);
    let mut kept = arrays(&p, &pos);
    assert_eq!(
        transform_counts(&kept.reals),
        None,
        "zeroed arrays hold none"
    );
    for k in 0..5 {
        let after = step_on(&p, &pos, &mut kept);
        let fresh = step_on(&p, &pos, &mut arrays(&p, &pos));
        assert!(after == fresh, "step {k}: kept and fresh transforms differ");
        pos = from_bits(&after);
    }
    let c = counts(&kept);
    // Each step takes several products (the matrix-free step's), all over one transform
    // while the rounded edges stay: at least one step in five kept the previous one's.
    assert!(c.computed < 5, "{c:?}");
    assert!(c.kept > 0, "{c:?}");
}

#[test]
fn a_moved_cloud_keeps_a_stretched_one_computes() {
    let p = params();
    let pos = ball(300);
    // Stretched by a quarter along x: past any rounding step (at most 1/16 of the edge).
    let wide: Vec<V> = pos
        .iter()
        .map(|r| f64::v3(1.25 * f64::xyz(*r)[0], f64::xyz(*r)[1], f64::xyz(*r)[2]))
        .collect();
    let both = [&pos[..], &wide[..]];
    let mut a = arrays_for(&p, &both);
    step_on(&p, &pos, &mut a);
    let c0 = counts(&a);
    assert_eq!(c0.computed, 1);
    // Moved as a whole by an offset no multiple of anything: the same edges.
    let moved: Vec<V> = pos
        .iter()
        .map(|r| *r + f64::v3(13.37, -7.1, 101.9))
        .collect();
    let kept = step_on(&p, &moved, &mut a);
    let c1 = counts(&a);
    assert_eq!(c1.computed, 1, "{c1:?}");
    assert!(c1.kept > c0.kept, "{c1:?}");
    assert!(kept == step_on(&p, &moved, &mut arrays_for(&p, &both)));
    let stretched = step_on(&p, &wide, &mut a);
    let c2 = counts(&a);
    assert_eq!(c2.computed, c1.computed + 1, "{c2:?}");
    assert!(stretched == step_on(&p, &wide, &mut arrays_for(&p, &both)));
}

#[test]
fn other_content_holds_no_transform() {
    // 50 spheres in a ball of radius 10.
    let n = 50;
    let pos = ball(n);
    let rad = vec![1.0; n];
    let f: Vec<V> = (0..n).map(|i| f64::v3(1.0, (i % 5) as f64, -2.0)).collect();
    let ff = FreeFast::<f64>::new(1.0, 1e-4, [20.0; 3], n).unwrap();
    let z = ff.storage(n);
    let run = |fill: f64| {
        let mut a = Arrays::new(z);
        a.reals.fill(fill);
        let mut out = vec![V::ZERO; n];
        ff.apply(1.0, &pos, &rad, &f, &mut out, &mut a.storage())
            .unwrap();
        let c = transform_counts(&a.reals).unwrap();
        (out, c)
    };
    let (zero, c) = run(0.0);
    assert_eq!(
        c,
        TransformCounts {
            kept: 0,
            computed: 1
        }
    );
    for fill in [1.0, 7.0, -1.0, f64::NAN] {
        let (out, c) = run(fill);
        assert_eq!(c.computed, 1, "fill {fill}: {c:?}");
        let same = out
            .iter()
            .zip(&zero)
            .all(|(a, b)| f64::xyz(*a) == f64::xyz(*b));
        assert!(same, "fill {fill}");
    }
}

#[test]
fn edges_round_up_to_a_coarse_step() {
    let a = 1.0;
    let mut last = 0.0;
    let mut e = 0.0;
    while e < 5000.0 {
        let r = round_extent(e, a);
        assert!(r >= e && r <= e + (e / 16.0).max(a), "{e} -> {r}");
        assert!(r >= last, "nondecreasing at {e}");
        // The same for every edge between the last rounded value and this one.
        assert_eq!(round_extent(r, a), r, "{e}");
        last = r;
        e += 0.37;
    }
    // The step: one radius for small clouds, a power of two times it for large ones.
    assert_eq!(round_extent(10.2, 1.0), 11.0);
    assert_eq!(round_extent(100.5, 1.0), 104.0);
    assert_eq!(round_extent(100.5, 0.5), 104.0);
}
