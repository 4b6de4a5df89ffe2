//! Tests of the weighing before each step: the pair count against a count of every
//! pair, the first step's choice against the cost model's, and the path a cloud with a
//! tail takes.

use hydrorattle::{Method, Params, Real};

use super::free_cost::FreeChoice;
use super::free_reweigh::{Reweigh, SAMPLED, count_pairs};

/// `n` points uniform in a ball of radius `r` about the origin (unit spheres, their
/// overlaps not removed: the weighing reads the centres only).
fn ball(n: usize, r: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut g = hydrorattle::Noise::new(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = [0; 3].map(|_| r * (2.0 * g.uniform() - 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= r * r {
            out.push(p);
        }
    }
    out
}

/// The fast product's first-order deterministic step parameters at tolerance 1e-4.
fn fast() -> Params<f64> {
    let mut p = Params::<f64>::new(0.05);
    p.method = Method::Overdamped;
    p.matrix_free = true;
    p.pse = Some(1e-4);
    p
}

/// The points as the kernel's vectors.
fn vs(pos: &[[f64; 3]]) -> Vec<<f64 as Real>::V3> {
    pos.iter().map(|&p| f64::v3_from(p)).collect()
}

fn brute(pos: &[[f64; 3]], r_cut: f64) -> u64 {
    let mut c = 0;
    for i in 0..pos.len() {
        for j in i + 1..pos.len() {
            let r2: f64 = (0..3).map(|a| (pos[i][a] - pos[j][a]).powi(2)).sum();
            c += u64::from(r2 < r_cut * r_cut);
        }
    }
    c
}

#[test]
fn the_count_is_every_pair_within_the_cutoff() {
    // A ball, a line and points on cell faces (negative coordinates included).
    let mut line: Vec<[f64; 3]> = (0..300)
        .map(|k| [0.7 * k as f64 - 100.0, 0.0, 1.0])
        .collect();
    line.extend((0..50).map(|k| [-2.0 * k as f64, 2.0, -4.0]));
    for pos in [ball(2000, 30.0, 7), line] {
        for r_cut in [0.5, 2.0, 4.0, 11.3] {
            let all = brute(&pos, r_cut);
            assert_eq!(count_pairs(&pos, r_cut, u64::MAX), all, "r_cut {r_cut}");
            // Stopped at a cap: the cap where the count reaches it, else the count.
            assert_eq!(count_pairs(&pos, r_cut, all), all);
            if all > 1 {
                assert_eq!(count_pairs(&pos, r_cut, all / 2), all / 2);
                assert_eq!(count_pairs(&pos, r_cut, all + 1), all);
            }
        }
    }
    assert_eq!(count_pairs(&[[0.0; 3]], 1.0, 9), 0);
    assert_eq!(count_pairs(&ball(10, 1.0, 1), 0.0, 9), 0);
}

/// Past [`SAMPLED`] spheres the count is an estimate from every k-th sphere's
/// neighbours: within 2 % of every pair counted, on a ball and on a ball with a tail
/// (a twentieth of its spheres strung out below it), and a ball's against its closed
/// form, `N^2 / 2` times the chance that two points of a ball of radius `R` lie within
/// `r`: `(r / R)^3 (1 - 9 r / (16 R) + r^3 / (32 R^3))`.
#[test]
fn past_the_sample_the_count_is_an_estimate() {
    let (n, r_ball) = (20000, 100.0);
    let pos = ball(n, r_ball, 3);
    let mut tail = pos.clone();
    for (i, p) in tail.iter_mut().take(n / 20).enumerate() {
        *p = [
            0.0,
            0.0,
            -r_ball - 2000.0 * (i + 1) as f64 / (n / 20) as f64,
        ];
    }
    for r in [4.0, 10.0, 25.0] {
        for (what, pos) in [("ball", &pos), ("tail", &tail)] {
            let all = brute(pos, r) as f64;
            let got = count_pairs(pos, r, u64::MAX) as f64;
            assert!(
                (got / all - 1.0).abs() < 0.02,
                "{what}, r {r}: {got} against {all}"
            );
        }
        let x = r / r_ball;
        let p = x.powi(3) * (1.0 - 9.0 * x / 16.0 + x.powi(3) / 32.0);
        let expect = 0.5 * (n * (n - 1)) as f64 * p;
        let got = count_pairs(&pos, r, u64::MAX) as f64;
        assert!(
            (got / expect - 1.0).abs() < 0.03,
            "r {r}: {got} against {expect}"
        );
    }
    assert!(n > SAMPLED);
}

fn weigh(w: &Reweigh, pos: &[[f64; 3]]) -> FreeChoice {
    let radius = vec![1.0; pos.len()];
    w.choose::<f64>(&vs(pos), &radius)
}

/// The count stopped at the tie decides as the whole count would: the faster of the
/// fast product (its pairs counted) and the pair sums by the cost model, for clouds on
/// both sides of the crossover.
#[test]
fn the_count_stopped_at_the_tie_decides_as_the_whole_count() {
    let p = fast();
    let w = Reweigh::new::<f64>(&p, 0).unwrap();
    let mut both = [false; 2];
    for (n, phi) in [
        (500, 0.01),
        (2000, 0.01),
        (5000, 0.01),
        (20000, 0.01),
        (3000, 0.2),
        (20000, 0.2),
    ] {
        let r = (n as f64 / phi).cbrt();
        let pos = ball(n, r, n as u64);
        let radius = vec![1.0; n];
        let [t_fast, t_sums] = w.modelled::<f64>(&vs(&pos), &radius).unwrap();
        let model = if t_fast < t_sums {
            FreeChoice::Fast
        } else {
            FreeChoice::MatrixFree
        };
        assert_eq!(
            weigh(&w, &pos),
            model,
            "{n} at {phi}: {t_fast:.3e} against {t_sums:.3e}"
        );
        both[usize::from(model == FreeChoice::Fast)] = true;
    }
    assert_eq!(both, [true; 2], "both paths taken somewhere");
}

/// A cloud that travels keeps the fast product; one whose tail stretches the box takes
/// the pair sums (the measured case: the fast product 11 times slower than the pair sums
/// on a 10^4-sphere cloud whose box has grown 100 times as tall).
#[test]
fn a_tail_turns_the_step_to_the_pair_sums() {
    let (n, r) = (10000, 101.0);
    let pos = ball(n, r, 11);
    let w = Reweigh::new::<f64>(&fast(), 0).unwrap();
    assert_eq!(weigh(&w, &pos), FreeChoice::Fast);
    let moved: Vec<_> = pos.iter().map(|p| [p[0] + 5e3, p[1], p[2] - 1e4]).collect();
    assert_eq!(weigh(&w, &moved), FreeChoice::Fast);
    // One sphere in twenty strung out below the ball, a tenth of its radius deep, and
    // 10^4 deep (the box 50 times as tall).
    for (depth, expect) in [(0.1 * r, FreeChoice::Fast), (1e4, FreeChoice::MatrixFree)] {
        let mut tail = pos.clone();
        let k = n / 20;
        for (i, p) in tail.iter_mut().take(k).enumerate() {
            *p = [0.0, 0.0, -r - depth * (i + 1) as f64 / k as f64];
        }
        assert_eq!(weigh(&w, &tail), expect, "tail {depth} deep");
    }
}

/// Only steps on the fast product in free space weigh.
#[test]
fn only_the_fast_product_weighs() {
    let mut p = fast();
    p.pse = None;
    assert!(Reweigh::new::<f64>(&p, 0).is_none());
    let mut p = fast();
    p.wall = Some(hydrorattle::Wall::new(-100.0));
    assert!(Reweigh::new::<f64>(&p, 0).is_none());
    assert!(Reweigh::new::<f64>(&fast(), 0).is_some());
}
