//! The paper's helix (`hydrorattle::helix`), written once for the host scenes and the
//! firmware: its bits pinned, every bond at its length to rounding, impossible helices
//! refused.

use hydrorattle::helix::{HeadEnd, Helix, HelixError};

/// Figure 1 (c) of the paper, as `host/scenes/figure1c.toml` and the firmware
/// build it.
const FIGURE1C: Helix = Helix {
    tails: 24,
    head_ratio: 2.0,
    dhat: 1.05,
    radius: 2.0,
    pitch: 7.0,
    head_end: HeadEnd::Bottom,
};

/// The scene files' default helix, head on top.
const DEFAULT_TOP: Helix = Helix {
    tails: 24,
    head_ratio: 1.259_921_049_894_873_2,
    dhat: 1.5,
    radius: 2.0,
    pitch: 7.0,
    head_end: HeadEnd::Top,
};

/// FNV-1a (64 bit) over the little-endian bits of every coordinate.
fn digest(h: &Helix) -> u64 {
    let mut d: u64 = 0xcbf2_9ce4_8422_2325;
    for c in h.positions().unwrap().flatten() {
        for b in c.to_bits().to_le_bytes() {
            d ^= u64::from(b);
            d = d.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    d
}

#[test]
fn the_positions_keep_their_bits() {
    // A change here changes every helix scene's output and the firmware's digest.
    assert_eq!(digest(&FIGURE1C), 0x989e_9dc3_46c6_7ae6);
    assert_eq!(digest(&DEFAULT_TOP), 0x9300_e003_c484_c40d);
}

#[test]
fn every_bond_has_its_length_to_rounding() {
    for h in [FIGURE1C, DEFAULT_TOP] {
        let mut positions = [[0.0; 3]; 25];
        let it = h.positions().unwrap();
        assert_eq!(it.len(), h.tails + 1);
        for (slot, p) in positions.iter_mut().zip(it) {
            *slot = p;
        }
        assert_eq!(positions[0], [0.0; 3]);
        for k in 0..h.tails {
            let [a, b] = [positions[k], positions[k + 1]];
            let d = libm::sqrt((0..3).map(|c| (a[c] - b[c]) * (a[c] - b[c])).sum());
            let want = h.dhat * (h.bead_radius(k) + h.bead_radius(k + 1));
            assert_eq!(h.bond_length(k), want);
            // Rounding of the coordinates themselves (up to ~20 high) bounds the error.
            let scale = a
                .iter()
                .chain(&b)
                .fold(want, |m, &c| libm::fmax(m, libm::fabs(c)));
            let tolerance = 4.0 * f64::EPSILON * scale;
            assert!(libm::fabs(d - want) < tolerance, "bond {k}: {d} vs {want}");
            // Tails on the cylinder, the head on the axis.
            let r = libm::hypot(b[0], b[1]);
            assert!(
                libm::fabs(r - h.radius) < 4.0 * f64::EPSILON * h.radius,
                "{k} {r}"
            );
        }
        // The head below (above) the first tail.
        let up = positions[1][2] > 0.0;
        assert_eq!(up, h.head_end == HeadEnd::Bottom);
    }
}

#[test]
fn impossible_helices_are_refused() {
    let no_tails = Helix {
        tails: 0,
        ..FIGURE1C
    };
    assert_eq!(no_tails.positions().err(), Some(HelixError::NoTails));
    let wide = Helix {
        radius: 4.0,
        ..FIGURE1C
    };
    assert!(matches!(
        wide.positions(),
        Err(HelixError::HeadTooShort { .. })
    ));
    let tight = Helix {
        radius: 0.5,
        pitch: 0.5,
        ..FIGURE1C
    };
    let Err(HelixError::TooTight { bond, max_chord }) = tight.angular_step() else {
        panic!("a half turn is shorter than the bond");
    };
    assert!(max_chord < bond);
    let nan = Helix {
        pitch: f64::NAN,
        ..FIGURE1C
    };
    assert!(nan.angular_step().is_err());
}
