//! The near field's far field is the geometry's own grand mobility, reached through the
//! kernel's geometry interface whichever way the far field is built: the bits of each
//! geometry's `assemble_grand`, the wall's height, and the box's minimum images.
#![cfg(feature = "near")]

use glam::{DMat3, DVec3};
use hydrorattle::Hydro;
use hydrorattle::geometry::{Named, Place};
use hydrorattle::linalg::tri;
use hydrorattle::stokesian::{Far, SdError};

const ETA: f64 = 0.8;

/// Three unequal spheres apart, above `z = 0`.
fn spheres() -> ([DVec3; 3], [f64; 3]) {
    let pos = [
        DVec3::new(0.3, -0.2, 1.4),
        DVec3::new(2.9, 0.4, 1.1),
        DVec3::new(-1.2, 2.6, 2.3),
    ];
    (pos, [0.5, 0.7, 0.4])
}

/// The packed grand mobility `far` gives, as bits.
fn grand(far: Far<'_, f64>) -> Result<Vec<[u64; 9]>, SdError> {
    let (pos, radius) = spheres();
    let mut out = vec![DMat3::ZERO; tri(2 * pos.len())];
    far.assemble_grand(ETA, &pos, &radius, &mut out)?;
    Ok(bits(&out))
}

fn bits(m: &[DMat3]) -> Vec<[u64; 9]> {
    m.iter()
        .map(|b| b.to_cols_array().map(f64::to_bits))
        .collect()
}

/// Free space: the RPY grand mobility, built as a constant or as a step's place.
#[test]
fn free_space_is_the_rpy_grand_mobility() -> Result<(), SdError> {
    let (pos, radius) = spheres();
    let mut want = vec![DMat3::ZERO; tri(2 * pos.len())];
    hydrorattle::mobility::assemble_grand(Hydro::Rpy, ETA, &pos, &radius, &mut want)
        .map_err(SdError::Particle)?;
    let step = Far::at(Place::new(Named::FREE), None).ok_or(SdError::Params)?;
    for far in [Far::FREE, step] {
        assert_eq!(grand(far)?, bits(&want));
        assert_eq!((far.wall(), far.cell()), (None, None));
        let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(9.0, -8.0, 7.0));
        assert_eq!(far.separation(a, b), b - a);
    }
    Ok(())
}

/// Above the wall: the wall's grand mobility (Blake's images), with the kernel's `wall`
/// feature; without it the far field refuses the wall rather than take free space.
#[test]
fn above_the_wall_is_the_walls_grand_mobility() -> Result<(), SdError> {
    let (pos, radius) = spheres();
    let h = 0.25;
    let mut want = vec![DMat3::ZERO; tri(2 * pos.len())];
    hydrorattle::mobility::wall::assemble_grand(Hydro::Rpy, ETA, h, &pos, &radius, &mut want)
        .map_err(SdError::Particle)?;
    let place = Place::new(Named {
        wall: Some(h),
        ..Named::FREE
    });
    let step = Far::at(place, None).ok_or(SdError::Params)?;
    for far in [Far::above(h), step] {
        assert_eq!(far.wall(), Some(h));
        match cfg!(feature = "wall") {
            true => assert_eq!(grand(far)?, bits(&want)),
            false => assert_eq!(grand(far), Err(SdError::Params)),
        }
    }
    // A centre below the wall is the far field's refusal, typed.
    let below = [DVec3::new(0.0, 0.0, -1.0)];
    let mut out = vec![DMat3::ZERO; tri(2)];
    let r = Far::above(h).assemble_grand(ETA, &below, &[0.5], &mut out);
    assert!(
        matches!(r, Err(SdError::Particle(_) | SdError::Params)),
        "{r:?}"
    );
    Ok(())
}

/// In the box: the Ewald sums' grand mobility and minimum images, built from the sums
/// (`Far::periodic`, `From`) or as a step's place with its sums; a box without its sums
/// has no far field.
#[cfg(feature = "periodic")]
#[test]
fn in_the_box_is_the_ewald_grand_mobility() -> Result<(), SdError> {
    use hydrorattle::cell::Periodic;
    use hydrorattle::geometry::sums::BoxSums;
    use hydrorattle::mobility::periodic::{Ewald, assemble_grand};
    let (pos, radius) = spheres();
    let cell = Periodic::new([6.0, 7.0, 8.0]).map_err(|e| SdError::Far(e.into()))?;
    let ew = Ewald::new(cell, 0.7).map_err(|e| SdError::Far(e.into()))?;
    let mut want = vec![DMat3::ZERO; tri(2 * pos.len())];
    assemble_grand(&ew, ETA, &pos, &radius, &mut want).map_err(|e| SdError::Far(e.into()))?;
    let place = Place::new(Named {
        cell: Some(cell),
        ..Named::FREE
    });
    let step = Far::at(place, Some(BoxSums::Ewald(&ew))).ok_or(SdError::Params)?;
    for far in [Far::periodic(&ew), Far::from(&ew), step] {
        assert_eq!(grand(far)?, bits(&want));
        assert_eq!((far.wall(), far.cell()), (None, Some(cell)));
        let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(5.9, -6.8, 7.9));
        // The minimum image of `(5.8, -7.0, 7.6)` in the box `6 x 7 x 8`.
        let image = far.separation(a, b) - DVec3::new(-0.2, 0.0, -0.4);
        assert!(image.length() < 1e-12, "{image}");
    }
    assert!(Far::at(place, None).is_none());
    Ok(())
}

/// A far field may cross threads (the Python package forms `M_SD` with the interpreter
/// released): it holds the box's Ewald sums, not a step's PSE storage.
#[test]
fn a_far_field_is_send_and_sync() {
    fn crosses<S: Send + Sync>(_: S) {}
    crosses(Far::<f64>::FREE);
    crosses(Far::above(0.5f32));
}
