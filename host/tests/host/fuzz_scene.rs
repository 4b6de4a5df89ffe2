//! Fuzzing the scene parser with a fixed seed: mutated copies of every shipped scene,
//! every bad scene (`host-demo/tests/data/bad`) and the seeds of `host/tests/data/fuzz` (which cover every table: the
//! wall, Brownian noise by Cholesky and by Lanczos, FENE, rest length 0, matrix-free,
//! rotation, hard contacts, f32, a periodic box by the Ewald sum and by PSE, a
//! suspension; each must be among the accepted cases) (lines deleted, duplicated, swapped or cut; numbers replaced by
//! hostile ones; keys, tables and bytes, invalid UTF-8 included, inserted). Every case
//! must return without a panic; a refusal must name the origin and a line inside the
//! text, in one line; an accepted scene must hold its invariants and write itself
//! back (`to_toml`) as a file that parses to the same scene.
//!
//! 100 000 cases by default (`FUZZ_CASES`, `FUZZ_SEED` to change; a longer run is
//! documented in docs/VALIDATION.md).

use std::path::PathBuf;

use hydrorattle_host::scene::{BoxMethod, Level, Precision, Scene, Sqrt};
use hydrorattle_host::sizing::Limits;

use crate::fuzz::{Rng, report, settings};

/// Picks one of `xs`.
trait Pick {
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str;
}

impl Pick for Rng {
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

const NUMBERS: [&str; 24] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "4294967296",
    "0.0",
    "1e200",
    "1e30",
    "1e39",
    "3",
    "0.5",
    "2.0",
    "1e-12",
    "1e9",
    "\"x\"",
    "[1, 2]",
    "true",
];

const SNIPPETS: [&str; 28] = [
    "[wall]\nheight = -5\n",
    "[box]\nsize = [12, 12, 12]\nmethod = \"pse\"\ntolerance = 1e-4\n",
    "[box]\nmethod = \"ewald\"\n",
    "[suspension]\ncount = 20\nfraction = 0.1\npolydispersity = 0.3\n",
    "method = \"pse\"\n",
    "tolerance = 1e-9\n",
    "fraction = 0.34\n",
    "sqrt = \"lanczos\"\n",
    "sqrt = \"cholesky\"\n",
    "fene = 4.0\n",
    "matrix_free = true\n",
    "rotation = true\n",
    "[helix]\ntails = 3\n",
    "[[particle]]\nposition = [0, 0, 0]\nradius = 1\n",
    "[[particle]]\nposition = [0.5, 0, 0]\nradius = 1\nvelocity = [1, 0, 0]\n",
    "[[bond]]\nbetween = [0, 1]\n",
    "[[bond]]\nbetween = [0, 99]\nlength = 1e200\n",
    "[model]\noverlap = \"allow\"\nlevel = \"auto\"\n",
    "[integrator]\nmethod = \"rattle\"\ndt = 0.01\nduration = 0.05\n",
    "[output]\nevery = 1\n",
    "[contact]\nstiffness = 100\n",
    "[brownian]\ntemperature = 0.5\nseed = 3\n",
    "precision = \"f32\"\n",
    "species = \"a b\"\n",
    "unknown = 1\n",
    "[[particle]]\n",
    "= = =\n",
    "# comment \u{e9}\n",
];

/// A mutation of `text`: one to four edits.
fn mutate(rng: &mut Rng, text: &str) -> Vec<u8> {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for _ in 0..1 + rng.below(4) {
        let n = lines.len();
        match rng.below(8) {
            0 if n > 0 => {
                lines.remove(rng.below(n));
            }
            1 if n > 0 => {
                let k = rng.below(n);
                lines.insert(rng.below(n + 1), lines[k].clone());
            }
            2 if n > 1 => {
                let (a, b) = (rng.below(n), rng.below(n));
                lines.swap(a, b);
            }
            3 | 4 if n > 0 => {
                // A value replaced by a hostile number or another type.
                let k = rng.below(n);
                if let Some((key, _)) = lines[k].split_once('=') {
                    lines[k] = format!("{key}= {}", rng.pick(&NUMBERS));
                }
            }
            5 => {
                let at = rng.below(n + 1);
                lines.insert(at, rng.pick(&SNIPPETS).trim_end().to_string());
            }
            6 if n > 0 => {
                let k = rng.below(n);
                let cut = rng.below(lines[k].len() + 1);
                let cut = (0..=cut).rev().find(|&c| lines[k].is_char_boundary(c));
                lines[k].truncate(cut.unwrap_or(0));
            }
            _ => {}
        }
    }
    let mut bytes = lines.join("\n").into_bytes();
    if rng.below(20) == 0 {
        // A stray byte: often not UTF-8.
        let at = rng.below(bytes.len() + 1);
        bytes.insert(at, (rng.next() & 0xFF) as u8);
    }
    bytes
}

fn corpus() -> Vec<String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut texts = Vec::new();
    for dir in ["scenes", "../host-demo/tests/data/bad", "tests/data/fuzz"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        texts.extend(files.iter().map(|p| std::fs::read_to_string(p).unwrap()));
    }
    texts
}

/// The features the accepted cases must cover, and whether scene `s` has each.
type Feature = (&'static str, fn(&Scene) -> bool);

const FEATURES: [Feature; 12] = [
    ("wall", |s| s.wall.is_some()),
    ("noise by Cholesky", |s| noise(s, Sqrt::Cholesky)),
    ("noise by Lanczos", |s| noise(s, Sqrt::Lanczos)),
    ("FENE", |s| s.integrator.fene.is_some()),
    ("rest length 0", |s| s.bonds.iter().any(|b| b.length == 0.0)),
    ("matrix-free", |s| s.integrator.matrix_free),
    ("rotation", |s| s.model.rotation),
    ("contacts", |s| s.contact.is_some()),
    ("f32", |s| s.integrator.precision == Precision::F32),
    ("periodic box", |s| s.periodic.is_some()),
    ("box by PSE", |s| {
        s.periodic.is_some_and(|b| b.method == BoxMethod::Pse)
    }),
    ("suspension", |s| s.suspension.is_some()),
];

fn noise(s: &Scene, sqrt: Sqrt) -> bool {
    s.brownian
        .is_some_and(|b| b.temperature > 0.0 && b.sqrt == sqrt)
}

/// Checks one case; `Err` describes a broken promise. `Ok(Some(scene))` when accepted.
fn case(bytes: &[u8], limits: Limits) -> Result<Option<Scene>, String> {
    let lines = bytes.split(|&b| b == b'\n').count();
    match Scene::parse_bytes(bytes, "fuzz.toml", limits) {
        Err(e) => {
            let shown = e.to_string();
            if !shown.starts_with("fuzz.toml:") || shown.contains('\n') || e.message.is_empty() {
                return Err(format!("badly formed error {shown:?}"));
            }
            match e.line() {
                Some(l) if l == 0 || l > lines + 1 => {
                    Err(format!("line {l} outside the {lines} lines: {shown}"))
                }
                _ => Ok(None),
            }
        }
        Ok(s) => {
            let n = s.particles.len();
            // Springs may rest at length zero; rigid bonds may not.
            let springs = s.integrator.method == hydrorattle_host::scene::Method::Springs;
            let ok = n > 0
                && s.species.len() == n
                && s.particles
                    .iter()
                    .all(|p| p.radius > 0.0 && p.density >= 0.0)
                && s.bonds.iter().all(|b| {
                    b.i < n
                        && b.j < n
                        && b.i != b.j
                        && (b.length > 0.0 || springs && b.length == 0.0)
                })
                && s.integrator.dt > 0.0
                && s.integrator.steps() >= 1
                && s.output.every >= 1;
            if !ok {
                return Err("accepted a scene that breaks an invariant".into());
            }
            // As a run writes its scene.toml: the level's choice applied, then manual.
            let (mut want, _) = hydrorattle_host::sim::resolve_level(&s, "fuzz");
            want.model.level = Level::Manual;
            let text = want.to_toml();
            match Scene::parse_limited(&text, "written.toml", limits) {
                Ok(back) if back == want => Ok(Some(s)),
                Ok(_) => Err(format!("to_toml does not read back the same:\n{text}")),
                Err(e) => Err(format!("to_toml writes a refused file: {e}\n{text}")),
            }
        }
    }
}

#[test]
fn the_parser_survives_mutated_scenes() {
    let (cases, seed) = settings(0x5CE_4E11);
    let texts = corpus();
    // Small limits keep every case fast (a mutated helix of 10^4 tails is refused).
    let limits = Limits {
        storage: 16 << 20,
        output: 1 << 30,
    };
    let (mut accepted, mut failures) = (0u64, Vec::new());
    let mut covered = [0u64; FEATURES.len()];
    for k in 0..cases {
        let mut rng = Rng::case(seed, k);
        let text = &texts[rng.below(texts.len())];
        let bytes = mutate(&mut rng, text);
        match std::panic::catch_unwind(|| case(&bytes, limits)) {
            Ok(Ok(Some(s))) => {
                accepted += 1;
                for (c, (_, has)) in covered.iter_mut().zip(FEATURES) {
                    *c += u64::from(has(&s));
                }
            }
            Ok(Ok(None)) => {}
            Ok(Err(m)) => failures.push(format!("case {k}: {m}")),
            Err(_) => failures.push(format!(
                "case {k}: panicked on {:?}",
                String::from_utf8_lossy(&bytes)
            )),
        }
    }
    let tally: Vec<String> = FEATURES
        .iter()
        .zip(covered)
        .map(|((f, _), c)| format!("{f} {c}"))
        .collect();
    eprintln!("fuzz_scene: accepted cases with {}", tally.join(", "));
    // A short run (`FUZZ_CASES`) may miss some; the default run must not.
    if cases >= 10_000 {
        for ((f, _), c) in FEATURES.iter().zip(covered) {
            if c == 0 {
                failures.push(format!("no accepted case has {f}"));
            }
        }
    }
    let name = format!("fuzz_scene ({} files)", texts.len());
    report(&name, cases, seed, accepted, &failures);
}
