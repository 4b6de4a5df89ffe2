//! A system's checks where a front end builds or loads it: pairs through the box's
//! faces, contact capacities past counting, saved records damaged, carrying pins or a
//! slit.

use hydrorattle::{Bond, Contacts, Noise, ParticleError, Periodic, StepError};

use super::{Beads, BuildError, Engine, Saved};
use crate::scene::{Precision, Scene};
use crate::sizing::DEFAULT_LIMIT;

fn beads(pos: &[[f64; 3]]) -> Beads<f64> {
    let n = pos.len();
    let pos = pos.iter().map(|&p| p.into()).collect();
    Beads::at_rest(pos, vec![1.0; n], vec![2.0; n])
}

fn engine(pos: &[[f64; 3]], edit: impl FnOnce(&mut hydrorattle::Params<f64>)) -> Engine<f64> {
    chain(pos, Vec::new(), edit)
}

fn chain(
    pos: &[[f64; 3]],
    bonds: Vec<Bond<f64>>,
    edit: impl FnOnce(&mut hydrorattle::Params<f64>),
) -> Engine<f64> {
    let mut p = hydrorattle::Params::new(0.1);
    edit(&mut p);
    Engine::from_parts(beads(pos), bonds, p, Noise::new(1), None, DEFAULT_LIMIT).unwrap()
}

#[test]
fn spheres_overlapping_through_a_face_are_refused_by_the_check() {
    // 0.8 apart through the face x = 0, 9.2 apart in free space.
    let pos = [[0.5, 5.0, 5.0], [9.7, 5.0, 5.0]];
    let boxed = |p: &mut hydrorattle::Params<f64>| p.periodic = Periodic::new([10.0; 3]).ok();
    let e = engine(&pos, boxed).check();
    assert_eq!(
        e,
        Err(StepError::Particle(ParticleError::Overlap { i: 0, j: 1 }))
    );
    assert_eq!(engine(&pos, |_| {}).check(), Ok(()));
}

#[test]
fn a_contact_capacity_past_counting_is_too_large_not_wrapped() {
    let mut p = hydrorattle::Params::<f64>::new(0.1);
    p.contacts = Some(Contacts::new(1 << 32));
    let pos = [[0.0; 3], [3.0, 0.0, 0.0]];
    match Engine::from_parts(
        beads(&pos),
        Vec::new(),
        p,
        Noise::new(1),
        None,
        DEFAULT_LIMIT,
    ) {
        Err(BuildError::TooLarge(t)) => assert_eq!(t.bytes, None),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a capacity of 2^32 was sized"),
    }
}

/// The record of `e` as JSON, changed by `edit`, loaded back.
fn reloaded(
    e: &Engine<f64>,
    edit: impl FnOnce(&mut serde_json::Value),
) -> Result<Engine<f64>, String> {
    let mut v = serde_json::to_value(e.save(Precision::F64)).unwrap();
    edit(&mut v);
    let saved: Saved = serde_json::from_value(v).map_err(|e| format!("saved system: {e}"))?;
    Engine::restore(&saved)
}

#[test]
fn a_damaged_record_is_refused_on_load() {
    let pos = [[0.0; 3], [3.0, 0.0, 0.0], [6.0, 0.0, 0.0]];
    let bond = |i| Bond {
        i,
        j: i + 1,
        length: 3.0,
    };
    let mut e = chain(&pos, vec![bond(0), bond(1)], |_| {});
    e.step().unwrap();
    assert!(reloaded(&e, |_| {}).is_ok());
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit); 5] = [
        ("radius 0", |v| v["radius"][1] = 0u64.into()),
        ("dt 0", |v| v["params"]["dt"] = 0u64.into()),
        ("coincident", |v| v["pos"][3] = v["pos"][0].clone()),
        ("short multipliers", |v| {
            v["multipliers"].as_array_mut().unwrap().pop();
        }),
        ("unknown key", |v| v["colour"] = "red".into()),
    ];
    for (what, edit) in cases {
        let err = reloaded(&e, edit)
            .err()
            .unwrap_or_else(|| panic!("{what}: loaded"));
        assert!(err.starts_with("saved system"), "{what}: {err}");
    }
}

#[test]
fn pins_survive_a_save_and_restore() {
    let text = "[[particle]]\nposition = [0, 0, 0]\nradius = 1.0\ndensity = 2.0\nfixed = true\n\n\
                [[particle]]\nposition = [0, 0, 2.5]\nradius = 1.0\ndensity = 2.0\n\n\
                [contact]\nmodel = \"hard\"\n\n\
                [integrator]\nmethod = \"overdamped\"\ndt = 0.05\nduration = 1.0\n";
    let scene = Scene::parse(text, "pinned.toml").unwrap();
    let mut a = Engine::<f64>::new(&scene, DEFAULT_LIMIT).unwrap();
    a.step().unwrap();
    let mut b = reloaded(&a, |_| {}).unwrap();
    assert_eq!(b.pins, a.pins);
    for _ in 0..5 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert_eq!(a.beads.pos, b.beads.pos);
    // The pinned sphere stayed where it was put; the other one settled onto it.
    assert_eq!(b.beads.pos[0], [0.0; 3].into());
}

#[test]
fn spheres_in_contact_within_the_tolerance_load() {
    // Touching to within the solver's tolerance, as a step with hard contacts leaves
    // them: a state a step accepted loads; without contacts the overlap is refused.
    let pos = [[0.0; 3], [2.0 - 1e-12, 0.0, 0.0]];
    let contacts = engine(&pos, |p| p.contacts = Some(Contacts::new(4)));
    assert!(reloaded(&contacts, |_| {}).is_ok());
    let plain = engine(&pos, |_| {});
    let err = reloaded(&plain, |_| {}).err().expect("an overlap loaded");
    assert!(err.contains("overlap"), "{err}");
}

#[test]
fn a_huge_until_is_printed_short() {
    // A run with a checkpoint, resumed to 1e300: refused, and the message says 1e300
    // (Display would print its 301 digits).
    let dir = std::env::temp_dir().join(format!("resume-until-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let text = "[[particle]]\nposition = [0, 0, 0]\nradius = 1.0\ndensity = 2.0\n\n\
                [integrator]\nmethod = \"overdamped\"\ndt = 0.1\nduration = 1.0\n";
    let scene = Scene::parse(text, "one.toml").unwrap();
    let limits = crate::sizing::Limits::default();
    let opts = super::RunOptions::files(limits, Some(0.5), false);
    super::run(&scene, "one", Some(&dir), opts).unwrap();
    let opts = super::RunOptions::files(limits, None, false);
    let Err(e) = super::resume(&dir, 1e300, limits, opts) else {
        panic!("resumed to 1e300");
    };
    let message = format!("{e:#}");
    let _ = std::fs::remove_dir_all(&dir);
    let digits = message.chars().fold((0, 0), |(run, most), c| {
        let run = if c.is_ascii_digit() { run + 1 } else { 0 };
        (run, most.max(run))
    });
    assert!(message.contains("1e300") && digits.1 < 30, "{message}");
}

/// A system in a slit keeps its slit through a save and restore, and moves as before.
#[test]
fn a_slit_survives_a_save_and_restore() {
    let pos = [[0.0, 0.0, 2.0], [3.0, 0.0, 3.0]];
    let mut a = engine(&pos, |p| {
        p.slit = Some(hydrorattle::Slit {
            floor: -1.0,
            ceiling: 30.0,
        });
    });
    a.step().unwrap();
    let mut b = reloaded(&a, |_| {}).unwrap();
    assert_eq!(b.params, a.params);
    a.step().unwrap();
    b.step().unwrap();
    assert_eq!(a.beads.pos, b.beads.pos);
}
