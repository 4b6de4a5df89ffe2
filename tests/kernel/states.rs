//! The named states on synthetic shapes and hand-set numbers whose states are
//! known, with the boundary of every threshold; each test in f32 and f64.

use hydrorattle::Real;
use hydrorattle::bonds::Bond;
use hydrorattle::observables::{
    FrameState, Rotation, Shape, StateThresholds, is_rotating, state_name, state_of,
};

/// Bonds joining consecutive beads at their current distances.
fn chain<T: Real>(pos: &[T::V3]) -> Vec<Bond<T>> {
    (1..pos.len())
        .map(|i| Bond {
            i: i - 1,
            j: i,
            length: T::norm(pos[i] - pos[i - 1]),
        })
        .collect()
}

fn v<T: Real>(x: f64, y: f64, z: f64) -> T::V3 {
    T::v3_from([x, y, z])
}

fn down<T: Real>() -> T::V3 {
    v::<T>(0.0, 0.0, -1.0)
}

fn named<T: Real>(pos: &[T::V3], vel: &[T::V3]) -> FrameState {
    let mass = vec![T::ONE; pos.len()];
    let bonds = chain::<T>(pos);
    let cos = T::from_f64(0.9);
    let s = Shape::measure(pos, vel, &mass, &bonds, down::<T>(), cos);
    state_of(&s, &StateThresholds::default())
}

/// 25 beads on a horizontal circle of radius 4 about the z axis (an open ring: the
/// ends are neighbours).
fn ring<T: Real>() -> Vec<T::V3> {
    (0..25)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 25.0;
            v::<T>(4.0 * a.cos(), 4.0 * a.sin(), 0.0)
        })
        .collect()
}

fn shapes<T: Real>() {
    let still = |n: usize| vec![T::V3_ZERO; n];
    // Straight down: stretched.
    let line: Vec<T::V3> = (0..25).map(|k| v::<T>(0.0, 0.0, -2.0 * k as f64)).collect();
    assert_eq!(named::<T>(&line, &still(25)), FrameState::Stretched);
    // Straight at 45 degrees, still: none of the states.
    let tilted: Vec<T::V3> = (0..25)
        .map(|k| v::<T>(1.5 * k as f64, 0.0, -1.5 * k as f64))
        .collect();
    assert_eq!(named::<T>(&tilted, &still(25)), FrameState::Other);
    // A column of 12 vertical bonds above a knot: 12 more beads on a small circle.
    let mut column: Vec<T::V3> = (0..13)
        .map(|k| v::<T>(0.0, 0.0, 24.0 - 2.0 * k as f64))
        .collect();
    column.extend((1..=12).map(|k| {
        let a = std::f64::consts::TAU * k as f64 / 12.0;
        v::<T>(3.8 * (a.cos() - 1.0), 3.8 * a.sin(), 0.0)
    }));
    assert_eq!(named::<T>(&column, &still(25)), FrameState::ColumnOverKnot);
    // The same column over a straight horizontal tail (not compact): not a column.
    let mut flag: Vec<T::V3> = column[..13].to_vec();
    flag.extend((1..=12).map(|k| v::<T>(2.0 * k as f64, 0.0, 0.0)));
    assert_eq!(named::<T>(&flag, &still(25)), FrameState::Other);
    // A horizontal ring, still: folded; spinning about the vertical: rotating.
    let r = ring::<T>();
    assert_eq!(named::<T>(&r, &still(25)), FrameState::Folded);
    let w = T::from_f64(0.05);
    let spin: Vec<T::V3> = r
        .iter()
        .map(|&p| T::cross(v::<T>(0.0, 0.0, 1.0), p) * w)
        .collect();
    assert_eq!(named::<T>(&r, &spin), FrameState::Rotating);
    // Spinning about a horizontal axis is not a rotation about the vertical: the
    // horizontal motion is all along x, which a turn about z cannot explain.
    let flip: Vec<T::V3> = r
        .iter()
        .map(|&p| T::cross(v::<T>(0.0, 1.0, 0.0), p) * w)
        .collect();
    assert_eq!(named::<T>(&r, &flip), FrameState::Folded);
    // A ring rolling over itself: each bead turns about the core tangent through a
    // tube of radius 1 around the circle of radius 4.
    let (mut pos, mut vel) = (Vec::new(), Vec::new());
    for k in 0..25 {
        let th = std::f64::consts::TAU * k as f64 / 25.0;
        let ps = std::f64::consts::TAU * (7 * k) as f64 / 25.0;
        let radial = [th.cos(), th.sin(), 0.0];
        let rho = [radial[0] * ps.cos(), radial[1] * ps.cos(), ps.sin()];
        let tangent = [-th.sin(), th.cos(), 0.0];
        pos.push(v::<T>(
            4.0 * radial[0] + rho[0],
            4.0 * radial[1] + rho[1],
            rho[2],
        ));
        let t = T::v3_from(tangent);
        vel.push(T::cross(t, T::v3_from(rho)) * T::from_f64(0.3) + down::<T>());
    }
    assert_eq!(named::<T>(&pos, &vel), FrameState::RollingRing);
}

/// A shape with every number at a neutral value: open, tilted, still.
fn neutral<T: Real>() -> Shape<T> {
    let still = Rotation {
        rate: T::ZERO,
        coherence: T::ZERO,
    };
    Shape {
        extension: T::HALF,
        verticality: T::HALF,
        spin: still,
        poloidal: still,
        vertical_run: 0,
        bonds: 16,
        contour: T::from_f64(32.0),
        horizontal: T::from_f64(20.0),
        vertical: T::from_f64(10.0),
    }
}

fn boundaries<T: Real>() {
    let th = StateThresholds::<T>::default();
    let at = |f: &dyn Fn(&mut Shape<T>)| {
        let mut s = neutral::<T>();
        f(&mut s);
        state_of(&s, &th)
    };
    let x = T::from_f64;
    assert_eq!(at(&|_| ()), FrameState::Other);
    // Stretched: both at their thresholds; either just below is not.
    let stretched = |s: &mut Shape<T>| {
        s.verticality = x(0.95);
        s.extension = x(0.85);
    };
    assert_eq!(at(&stretched), FrameState::Stretched);
    assert_eq!(
        at(&|s| {
            stretched(s);
            s.verticality = x(0.94);
        }),
        FrameState::Other
    );
    assert_eq!(
        at(&|s| {
            stretched(s);
            s.extension = x(0.84);
        }),
        FrameState::Other
    );
    // Column: 6 bonds is a column, 5 is not; the knot (8 bonds of length 2 outside a
    // run of 8 of 16) may spread 0.5 x 16 = 8 across, not more; a run over every bond
    // is no column.
    let column = |run: usize, wide: f64| {
        move |s: &mut Shape<T>| {
            s.vertical_run = run;
            s.horizontal = x(wide);
        }
    };
    assert_eq!(at(&column(8, 8.0)), FrameState::ColumnOverKnot);
    assert_eq!(at(&column(8, 8.5)), FrameState::Other);
    assert_eq!(at(&column(6, 1.0)), FrameState::ColumnOverKnot);
    assert_eq!(at(&column(5, 1.0)), FrameState::Other);
    assert_eq!(at(&column(16, 0.0)), FrameState::Other);
    // Rolling ring: compact (extension 0.35), coherence 0.5, rate 0.01 (either sign).
    let rolling = |e: f64, c: f64, r: f64| {
        move |s: &mut Shape<T>| {
            s.extension = x(e);
            s.poloidal = Rotation {
                rate: x(r),
                coherence: x(c),
            };
        }
    };
    assert_eq!(at(&rolling(0.35, 0.5, -0.01)), FrameState::RollingRing);
    assert_eq!(at(&rolling(0.36, 0.5, 0.01)), FrameState::Other);
    assert_eq!(at(&rolling(0.35, 0.49, 0.01)), FrameState::Folded);
    assert_eq!(at(&rolling(0.35, 0.9, 0.009)), FrameState::Folded);
    // Rotating: coherence 0.5 and rate 0.002 (either sign), open or compact.
    let spinning = |c: f64, r: f64| {
        move |s: &mut Shape<T>| {
            s.spin = Rotation {
                rate: x(r),
                coherence: x(c),
            };
        }
    };
    assert_eq!(at(&spinning(0.5, -0.002)), FrameState::Rotating);
    assert_eq!(at(&spinning(0.49, 0.1)), FrameState::Other);
    assert_eq!(at(&spinning(0.9, 0.0019)), FrameState::Other);
    assert!(is_rotating(
        &Rotation {
            rate: x(0.002),
            coherence: x(0.5)
        },
        &th
    ));
    // The order: a stretched chain that spins is stretched; a compact one that spins
    // and rolls is a rolling ring; a compact one that only spins is rotating.
    assert_eq!(
        at(&|s| {
            stretched(s);
            spinning(0.9, 0.1)(s);
        }),
        FrameState::Stretched
    );
    assert_eq!(
        at(&|s| {
            rolling(0.1, 0.9, 0.1)(s);
            spinning(0.9, 0.1)(s);
        }),
        FrameState::RollingRing
    );
    assert_eq!(
        at(&|s| {
            rolling(0.1, 0.0, 0.0)(s);
            spinning(0.9, 0.1)(s);
        }),
        FrameState::Rotating
    );
    assert_eq!(at(&rolling(0.1, 0.0, 0.0)), FrameState::Folded);
}

macro_rules! state_tests {
    ($m:ident, $t:ty) => {
        mod $m {
            #[test]
            fn synthetic_shapes_get_their_states() {
                super::shapes::<$t>();
            }
            #[test]
            fn every_threshold_at_its_boundary() {
                super::boundaries::<$t>();
            }
        }
    };
}

state_tests!(f64_states, f64);
state_tests!(f32_states, f32);

#[test]
fn names_are_fixed_and_read_back() {
    let names: Vec<&str> = FrameState::ALL.iter().map(|&s| state_name(s)).collect();
    assert_eq!(
        names,
        [
            "stretched",
            "column_over_knot",
            "rolling_ring",
            "rotating",
            "folded",
            "other"
        ]
    );
    for (k, s) in FrameState::ALL.into_iter().enumerate() {
        assert_eq!(FrameState::from_name(s.name()), Some(s));
        assert_eq!(s.index(), k);
    }
    assert_eq!(FrameState::from_name("twisting"), None);
}
