//! Beyond the paper: the outcome map over (D, head ratio), and how robust each of the
//! paper's outcomes and claims is to the choices the paper leaves unstated.

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::style::RGBColor;
use rayon::prelude::*;

use crate::claims::{CaseRun, claim_tables};
use crate::render::{CategoryMap, Mark, category_map};
use hydrorattle_host::output::{AtomicFile, CsvWriter};
use hydrorattle_host::progress::Progress;
use hydrorattle_host::scene::{HeadEnd, Helix, Hydrodynamics, Method, Scene};
use hydrorattle_host::sim::{Observables, RunOptions, Summary, run};

/// Outcome names (the late states, in `State::ALL` order, and "failed") in map order,
/// with their colours.
const CATEGORIES: [(&str, RGBColor); 7] = [
    ("stretched", RGBColor(230, 159, 0)),
    ("column_over_knot", RGBColor(0, 158, 115)),
    ("rolling_ring", RGBColor(204, 121, 167)),
    ("rotating", RGBColor(86, 180, 233)),
    ("folded", RGBColor(0, 114, 178)),
    ("other", RGBColor(160, 160, 160)),
    ("failed", RGBColor(200, 40, 40)),
];

/// `template` with its helix replaced by `helix` (particles and bonds regenerated).
pub fn with_helix(template: &Scene, helix: Helix) -> Result<Scene> {
    let chain = helix.generate().map_err(|e| anyhow!(e))?;
    let mut s = template.clone();
    s.particles = chain.particles();
    s.bonds = chain.scene_bonds();
    s.helix = Some(helix);
    Ok(s)
}

/// The summary and the observables series of a run (a failed one: empty series).
fn run_quiet(scene: &Scene, name: &str, max_steps: Option<usize>) -> (Summary, Vec<Observables>) {
    let opts = RunOptions {
        progress: false,
        max_steps,
        ..RunOptions::default()
    };
    match run(scene, name, None, opts) {
        Ok(r) => (r.summary, r.series),
        Err(e) => {
            log::warn!("{name}: {e:#}");
            (failed_summary(scene, name, &format!("{e:#}")), Vec::new())
        }
    }
}

fn failed_summary(scene: &Scene, name: &str, why: &str) -> Summary {
    Summary {
        outcome: "failed".to_string(),
        failure: Some(why.to_string()),
        ..Summary::for_scene(scene, name)
    }
}

/// Runs the `n x n` grid (D in [1.05, 2.0], head ratio in [1, 2.5]) from the Figure 1
/// (a) scene, writing `phase.csv` and `phase.png`.
pub fn phase(out: &Path, n: usize, max_steps: Option<usize>) -> Result<()> {
    std::fs::create_dir_all(out)?;
    let template = Scene::figure1()?.remove(0).1;
    let base = template
        .helix
        .ok_or_else(|| anyhow!("figure 1 scene without helix"))?;
    let (ds, hs) = (
        hydrorattle_host::sweep::linspace(1.05, 2.0, n),
        hydrorattle_host::sweep::linspace(1.0, 2.5, n),
    );
    let cells: Vec<(f64, f64)> = hs
        .iter()
        .flat_map(|&h| ds.iter().map(move |&d| (d, h)))
        .collect();
    let bar = Progress::new(cells.len() as u64, "phase");
    let results: Vec<Summary> = cells
        .par_iter()
        .map(|&(d, h)| {
            let name = format!("D={d:.3} head={h:.3}");
            let helix = Helix {
                dhat: d,
                head_ratio: h,
                ..base
            };
            let s = match with_helix(&template, helix) {
                Ok(scene) => run_quiet(&scene, &name, max_steps).0,
                Err(e) => failed_summary(&template, &name, &format!("{e:#}")),
            };
            bar.inc(1);
            s
        })
        .collect();
    bar.finish();
    let mut csv = CsvWriter::new(
        AtomicFile::create(&out.join("phase.csv"))?,
        &[
            "dhat",
            "head_ratio",
            "outcome",
            "extension",
            "verticality",
            "twist_rate",
            "head_speed",
            "failure",
        ],
    )?;
    for (&(d, h), s) in cells.iter().zip(&results) {
        let f = &s.final_observables;
        csv.write_record(&[
            format!("{d}"),
            format!("{h}"),
            s.outcome.clone(),
            format!("{}", f.extension),
            format!("{}", f.verticality),
            format!("{}", s.twist_rate),
            format!("{}", f.head_speed),
            s.failure.clone().unwrap_or_default(),
        ])?;
    }
    csv.into_inner().commit()?;
    let index = |o: &str| CATEGORIES.iter().position(|c| c.0 == o);
    let map = CategoryMap {
        title: match max_steps {
            Some(m) => format!(
                "Late-state outcome of a settling 1+24 bead helix [QUICK: {m} steps per cell]"
            ),
            None => "Late-state outcome of a settling 1+24 bead helix".to_string(),
        },
        x_label: "D = bond length / (a_i + a_j)".to_string(),
        y_label: "head radius / tail radius".to_string(),
        x: ds,
        y: hs,
        cells: results.iter().map(|s| index(&s.outcome)).collect(),
        categories: CATEGORIES
            .iter()
            .map(|(n, c)| (n.to_string(), *c))
            .collect(),
        marks: [
            (1.50, 2f64.cbrt(), "a"),
            (1.05, 2f64.cbrt(), "b"),
            (1.05, 2.0, "c"),
        ]
        .iter()
        .map(|&(x, y, l)| Mark {
            x,
            y,
            label: format!("paper ({l})"),
        })
        .collect(),
    };
    category_map(&out.join("phase.png"), &map, (900, 760))?;
    Ok(())
}

/// A change to a scene.
type Change = Box<dyn Fn(&Scene) -> Result<Scene> + Sync>;

/// One variant of the sensitivity study: a name, the value it sets, and the change.
type Variant = (&'static str, String, Change);

fn helix_variant(f: impl Fn(&mut Helix) + Sync + 'static) -> Change {
    Box::new(move |s: &Scene| {
        let mut h = s.helix.ok_or_else(|| anyhow!("no helix"))?;
        f(&mut h);
        with_helix(s, h)
    })
}

fn variants() -> Vec<Variant> {
    let mut v: Vec<Variant> = vec![(
        "baseline",
        String::new(),
        Box::new(|s: &Scene| Ok(s.clone())),
    )];
    for r in [1.5, 2.3] {
        v.push((
            "helix_radius",
            format!("{r}"),
            helix_variant(move |h| h.radius = r),
        ));
    }
    for p in [4.5, 10.0] {
        v.push(("pitch", format!("{p}"), helix_variant(move |h| h.pitch = p)));
    }
    v.push((
        "head_end",
        "top".into(),
        helix_variant(|h| h.head_end = HeadEnd::Top),
    ));
    v.push((
        "contact",
        "off".into(),
        Box::new(|s: &Scene| {
            let mut s = s.clone();
            s.contact = None;
            Ok(s)
        }),
    ));
    v.push((
        "contact",
        "soft_first_order".into(),
        Box::new(|s: &Scene| {
            // The earlier main job: soft contact, first order, dt = 0.005.
            let mut s = s.clone();
            s.with_soft_contact();
            s.integrator.method = Method::Overdamped;
            Ok(s)
        }),
    ));
    v.push((
        "dt",
        "halved".into(),
        Box::new(|s: &Scene| {
            let mut s = s.clone();
            s.integrator.dt *= 0.5;
            s.output.every *= 2;
            Ok(s)
        }),
    ));
    v.push((
        "duration",
        "doubled".into(),
        Box::new(|s: &Scene| {
            let mut s = s.clone();
            s.integrator.duration *= 2.0;
            s.output.every *= 2;
            Ok(s)
        }),
    ));
    v.push((
        "hydrodynamics",
        "free_draining".into(),
        Box::new(|s: &Scene| {
            let mut s = s.clone();
            s.model.hydrodynamics = Hydrodynamics::FreeDraining;
            Ok(s)
        }),
    ));
    for st in [0.1, 1.0, 3.0, 10.0] {
        v.push((
            "stokes_number",
            format!("{st}"),
            Box::new(move |s: &Scene| stokes(s, st)),
        ));
    }
    v
}

/// The same weights with inertia: density `4.5 St`, gravity `1 / St` (docs/MODEL.md#units),
/// integrated with the stable-drag RATTLE.
fn stokes(s: &Scene, st: f64) -> Result<Scene> {
    let mut s = s.clone();
    let scale = st; // density 4.5 -> 4.5 St, gravity 1 -> 1 / St: same weights.
    for p in &mut s.particles {
        p.density *= scale;
    }
    for g in &mut s.gravity {
        *g /= scale;
    }
    if let Some(h) = s.helix.as_mut() {
        h.density *= scale;
    }
    s.model.inertia = true;
    s.integrator.method = Method::RattleStable;
    // Hard contacts are for the overdamped methods: the inertial runs keep the soft one.
    s.with_soft_contact();
    Ok(s)
}

/// Runs every variant on the three Figure 1 cases; writes `sensitivity.csv` (per case
/// and variant), `claims_variants.csv` (every claim's verdict per variant) and
/// `claims_sensitivity.csv` (per claim, in how many variants it holds), and returns the
/// last as a printable table.
pub fn sensitivity(out: &Path, max_steps: Option<usize>) -> Result<String> {
    std::fs::create_dir_all(out)?;
    let cases = Scene::figure1()?;
    let vars = variants();
    let jobs: Vec<(usize, usize)> = (0..cases.len())
        .flat_map(|c| (0..vars.len()).map(move |v| (c, v)))
        .collect();
    let bar = Progress::new(jobs.len() as u64, "sensitivity");
    let results: Vec<(Summary, Vec<Observables>)> = jobs
        .par_iter()
        .map(|&(c, v)| {
            let (case, scene) = &cases[c];
            let (what, value, change) = &vars[v];
            let name = format!("{case} {what}={value}");
            let s = match change(scene) {
                Ok(sc) => run_quiet(&sc, &name, max_steps),
                Err(e) => (failed_summary(scene, &name, &format!("{e:#}")), Vec::new()),
            };
            bar.inc(1);
            s
        })
        .collect();
    bar.finish();
    let mut csv = CsvWriter::new(
        AtomicFile::create(&out.join("sensitivity.csv"))?,
        &[
            "case",
            "parameter",
            "value",
            "outcome",
            "extension",
            "verticality",
            "twist_rate",
            "head_speed",
            "front_correlation",
            "wall_s",
            "failure",
        ],
    )?;
    for (&(c, v), (s, _)) in jobs.iter().zip(&results) {
        let f = &s.final_observables;
        csv.write_record(&[
            cases[c].0.to_string(),
            vars[v].0.to_string(),
            vars[v].1.clone(),
            s.outcome.clone(),
            format!("{:.4}", f.extension),
            format!("{:.4}", f.verticality),
            format!("{:.5}", s.twist_rate),
            format!("{:.4}", f.head_speed),
            format!("{:.3}", s.front.correlation),
            format!("{:.2}", s.wall_time_s),
            s.failure.clone().unwrap_or_default(),
        ])?;
    }
    csv.into_inner().commit()?;
    let names: Vec<(String, String)> = vars
        .iter()
        .map(|v| (v.0.to_string(), v.1.clone()))
        .collect();
    let runs: Vec<Vec<CaseRun<'_>>> = (0..vars.len())
        .map(|v| {
            jobs.iter()
                .zip(&results)
                .filter(|(j, _)| j.1 == v)
                .map(|(j, (s, series))| CaseRun {
                    case: cases[j.0].0,
                    series,
                    front: &s.front,
                })
                .collect()
        })
        .collect();
    claim_tables(out, &names, &runs)
}
