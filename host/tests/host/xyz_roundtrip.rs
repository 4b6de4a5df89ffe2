//! Extended XYZ trajectories: written through an atomic file and read back bit-exact.

use hydrorattle_host::output::{
    AtomicFile, Frame, XYZ_PROPERTIES, XyzWriter, read_xyz_file, tmp_path,
};
use hydrorattle_host::scene::Scene;

/// A small deterministic generator (xorshift64*) of awkward doubles.
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        match bits % 8 {
            // Any finite double, from subnormals to the largest.
            0 => loop {
                let x = f64::from_bits(bits.rotate_left(17));
                if x.is_finite() {
                    break x;
                }
            },
            1 => -0.0,
            2 => 5e-324,
            _ => (bits >> 11) as f64 / (1u64 << 53) as f64 * 200.0 - 100.0,
        }
    }

    fn vec3(&mut self) -> [f64; 3] {
        [self.next(), self.next(), self.next()]
    }
}

#[test]
fn trajectory_round_trip_is_bit_exact() {
    let scene = Scene::figure1().unwrap().remove(0).1;
    let n = scene.particles.len();
    let mut numbers = Numbers(0x9e37_79b9_7f4a_7c15);
    let mut frames = Vec::new();
    for k in 0..5 {
        let mut positions = scene.positions();
        if k > 0 {
            positions.iter_mut().for_each(|p| *p = numbers.vec3());
        }
        frames.push(Frame {
            time: k as f64 * 0.1,
            species: scene.species().iter().map(|s| s.to_string()).collect(),
            positions,
            radii: scene.radii(),
            masses: scene.topology().mass,
            velocities: (0..n).map(|_| numbers.vec3()).collect(),
            cell: None,
        });
    }

    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("xyz_roundtrip");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("trajectory.xyz");
    let _ = std::fs::remove_file(&path);
    let mut writer = XyzWriter::new(AtomicFile::create(&path).unwrap());
    let topology = scene.topology();
    for f in &frames {
        writer
            .write_frame(&topology, f.time, &f.positions, &f.velocities)
            .unwrap();
    }
    assert!(
        !path.exists(),
        "nothing under the final name before the commit"
    );
    writer.into_inner().commit().unwrap();
    assert!(path.exists() && !tmp_path(&path).exists());

    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("25"));
    assert_eq!(
        lines.next(),
        Some(format!("Properties={XYZ_PROPERTIES} Time=0.0 pbc=\"F F F\"").as_str())
    );
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("head 0 0 0 1 1.2599210498948732 ")
    );
    assert!(lines.next().unwrap().starts_with("tail "));

    let back = read_xyz_file(&path).unwrap();
    assert_eq!(back.len(), frames.len());
    let bits3 = |v: &[[f64; 3]]| -> Vec<u64> { v.iter().flatten().map(|x| x.to_bits()).collect() };
    for (a, b) in frames.iter().zip(&back) {
        assert_eq!(a.time.to_bits(), b.time.to_bits());
        assert_eq!(a.species, b.species);
        assert_eq!(bits3(&a.positions), bits3(&b.positions));
        assert_eq!(bits3(&a.velocities), bits3(&b.velocities));
        let r = |v: &[f64]| -> Vec<u64> { v.iter().map(|x| x.to_bits()).collect() };
        assert_eq!(r(&a.radii), r(&b.radii));
        assert_eq!(r(&a.masses), r(&b.masses));
    }
}
