//! Owned storage for the iterative near field's solver, sized for the close pairs of
//! the spheres (shared by `#[path]` among the near-field examples).

use glam::DVec3;
use hydrorattle::stokesian::iterative::{Solver, Storage, count_pairs, sizes};
use hydrorattle::stokesian::{Far, NearField};

/// Storage sized for the close pairs of the spheres.
pub struct Store {
    pairs: Vec<[usize; 2]>,
    reals: Vec<f64>,
    field: Vec<DVec3>,
    cells: Vec<usize>,
}

impl Store {
    /// Counts the close pairs of `pos` and sizes the storage for them.
    pub fn new(far: Far<'_, f64>, pos: &[DVec3], rad: &[f64], near: NearField<f64>) -> Self {
        let n = pos.len();
        let mut cells = vec![0; 3 * n + 1];
        let np = count_pairs(far, pos, rad, near, &mut cells).expect("pairs");
        let (a, b, c, _) = sizes(n, np);
        Store {
            pairs: vec![[0; 2]; a],
            reals: vec![0.0; b],
            field: vec![DVec3::ZERO; c],
            cells,
        }
    }

    /// The solver at `pos` (viscosity 1), its close pairs found and factored.
    pub fn solver<'a>(
        &'a mut self,
        far: Far<'_, f64>,
        pos: &[DVec3],
        rad: &[f64],
        near: NearField<f64>,
    ) -> Solver<'a, f64> {
        let store = Storage {
            pairs: &mut self.pairs,
            reals: &mut self.reals,
            field: &mut self.field,
            cells: &mut self.cells,
        };
        Solver::new(1.0, far, pos, rad, near, store).expect("near field")
    }
}
