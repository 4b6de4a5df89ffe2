//! The cost of the box's grand mobility (`mobility::periodic::assemble_grand`, the far
//! field of a step with the iterative near field) against its translational blocks
//! alone (`assemble_tt`, what a RPY step assembles). Each pair's rotation blocks are
//! Ewald sums over the same real-space images and the same wave vectors as its
//! translational block; summed in the same pass they add their few products to each
//! term, not a second evaluation of every image's free-space blocks and every wave
//! vector's phase. So the grand assembly, four blocks a pair where `assemble_tt` forms
//! one, must cost well under twice `assemble_tt` (two full sums a pair cost 2.3 to 2.9
//! times, `examples/near_box_cost.rs`). Measured in this thread's CPU time (a loaded
//! machine's waits do not count), interleaved, the least of several rounds of each.
#![cfg(feature = "periodic")]

use hydrorattle::Periodic;
use hydrorattle::glam::{DMat3, DVec3};
use hydrorattle::linalg::tri;
use hydrorattle::mobility::periodic::{Ewald, assemble_grand, assemble_tt};

/// This thread's CPU time (user + system), seconds, from `/proc/thread-self/stat`
/// (clock ticks of 10 ms); `None` off Linux.
fn cpu() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// `n` spheres of radii 0.8 to 1.2 on a jittered cubic lattice at volume fraction
/// about 0.25 (every gap positive): positions, radii, edge.
fn suspension(n: usize) -> (Vec<DVec3>, Vec<f64>, f64) {
    let side = (n as f64).cbrt().ceil() as usize;
    // Lattice spacing for volume fraction 0.25 of unit spheres on a full lattice.
    let h = (4.0 / 3.0 * std::f64::consts::PI / 0.25).cbrt();
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut pos, mut rad) = (Vec::new(), Vec::new());
    for k in 0..n {
        let c = DVec3::new(
            (k % side) as f64,
            ((k / side) % side) as f64,
            (k / side / side) as f64,
        );
        let jitter = DVec3::new(uniform(), uniform(), uniform()) - 0.5;
        pos.push(c * h + jitter * 0.2);
        rad.push(0.8 + 0.4 * uniform());
    }
    (pos, rad, side as f64 * h)
}

// A timing, so run by hand (`-- --ignored grand_cost::`): on a shared machine CPU times
// of identical work differ by tens of percent, and the suite's checks must not depend
// on the load. The one-pass sums are checked bit for bit against the separate sums by
// `mobility::periodic::rot`'s unit test, which always runs.
#[test]
#[ignore = "a CPU-time ratio; run by hand on a quiet machine"]
fn box_grand_assembly_costs_well_under_two_tt_assemblies() {
    let Some(_) = cpu() else {
        return; // no per-thread CPU clock off Linux
    };
    let n = 160;
    let (pos, rad, l) = suspension(n);
    let ew = Ewald::new(Periodic::new([l; 3]).unwrap(), 1.2).unwrap();
    let mut tt = vec![DMat3::ZERO; tri(n)];
    let mut grand = vec![DMat3::ZERO; tri(2 * n)];
    let (mut t_tt, mut t_grand) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        let t = cpu().unwrap();
        assemble_tt(&ew, 1.0, &pos, &rad, &mut tt).unwrap();
        t_tt = t_tt.min(cpu().unwrap() - t);
        let t = cpu().unwrap();
        assemble_grand(&ew, 1.0, &pos, &rad, &mut grand).unwrap();
        t_grand = t_grand.min(cpu().unwrap() - t);
    }
    // The grand mobility's translational blocks are `assemble_tt`'s.
    for i in 0..n {
        for j in 0..=i {
            assert_eq!(grand[tri(i) + j], tt[tri(i) + j], "block ({i}, {j})");
        }
    }
    let ratio = t_grand / t_tt;
    println!("tt assembly {t_tt:.3} s, grand assembly {t_grand:.3} s: {ratio:.2}");
    assert!(t_tt > 0.05, "too short to time: {t_tt} s");
    assert!(ratio < 1.85, "grand assembly {ratio:.2} tt assemblies");
}
