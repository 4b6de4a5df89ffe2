//! A resolved scene written back as a scene file: every default and `auto` choice
//! spelled out, numbers in text that reads back to the same bits, so that the file
//! re-runs to the same result.

use serde::Serialize;
use toml::{Table, Value};

use super::{Level, Scene};

fn value<T: Serialize>(x: T) -> Value {
    Value::try_from(x).expect("scene values are TOML values")
}

fn table<const N: usize>(pairs: [(&str, Value); N]) -> Value {
    Value::Table(pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect())
}

impl Scene {
    /// The scene as a scene file that parses back to the same scene (with `level`
    /// manual: an `auto` choice is already applied by the caller).
    pub fn to_toml(&self) -> String {
        let mut t = Table::new();
        let f = &self.fluid;
        t.insert(
            "fluid".into(),
            table([
                ("viscosity", value(f.viscosity)),
                ("density", value(f.density)),
            ]),
        );
        t.insert(
            "gravity".into(),
            table([("acceleration", value(self.gravity))]),
        );
        t.insert(
            "flow".into(),
            table([
                ("velocity", value(self.flow.velocity)),
                ("vorticity", value(self.flow.vorticity)),
            ]),
        );
        let m = &self.model;
        t.insert(
            "model".into(),
            table([
                ("hydrodynamics", value(m.hydrodynamics.name())),
                ("inertia", value(m.inertia)),
                ("rotation", value(m.rotation)),
                ("level", value(Level::Manual)),
                ("overlap", value(m.overlap)),
            ]),
        );
        let i = &self.integrator;
        t.insert(
            "integrator".into(),
            table([
                ("method", value(i.method.name())),
                ("dt", value(i.dt)),
                ("duration", value(i.duration)),
                ("solver", value(i.solver.name())),
                ("tolerance", value(i.tolerance)),
                ("max_iterations", value(i.max_iterations as i64)),
                ("precision", value(i.precision)),
                ("stiffness", value(i.stiffness)),
                ("matrix_free", value(i.matrix_free)),
            ]),
        );
        // Written only when set: scenes written before the key stay the same.
        if let (Some(q0), Some(Value::Table(it))) = (i.fene, t.get_mut("integrator")) {
            it.insert("fene".into(), value(q0));
        }
        if let (true, Some(Value::Table(it))) = (i.compact_products, t.get_mut("integrator")) {
            it.insert("compact_products".into(), value(true));
        }
        t.insert(
            "output".into(),
            table([("every", value(self.output.every as i64))]),
        );
        match self.contact {
            Some(super::Contact::Soft { stiffness }) => {
                t.insert("contact".into(), table([("stiffness", value(stiffness))]));
            }
            Some(super::Contact::Hard { capacity: None }) => {
                t.insert("contact".into(), table([("model", value("hard"))]));
            }
            Some(super::Contact::Hard { capacity: Some(k) }) => {
                let c = table([("model", value("hard")), ("capacity", value(k as i64))]);
                t.insert("contact".into(), c);
            }
            None => {}
        }
        if let Some(b) = self.brownian {
            let mut bt = table([
                ("temperature", value(b.temperature)),
                ("seed", value(b.seed as i64)),
                ("drift", value(b.drift.name())),
            ]);
            // Written only when chosen: scenes written before the key stay the same.
            if let (Value::Table(m), false) = (&mut bt, b.sqrt == super::Sqrt::Auto) {
                m.insert("sqrt".into(), value(b.sqrt.name()));
            }
            t.insert("brownian".into(), bt);
        }
        if let Some(w) = self.wall {
            t.insert("wall".into(), table([("height", value(w.height))]));
        }
        if let Some(s) = self.slit {
            let st = table([("floor", value(s.floor)), ("ceiling", value(s.ceiling))]);
            t.insert("slit".into(), st);
        }
        if let Some(n) = self.near_field {
            let nt = table([
                ("cutoff", value(n.cutoff)),
                ("wall_cutoff", value(n.wall_cutoff)),
                ("min_gap", value(n.min_gap)),
            ]);
            t.insert("near_field".into(), nt);
        }
        if let Some(f) = self.free_space {
            let mut ft = table([
                ("method", value(f.method)),
                ("tolerance", value(f.tolerance)),
            ]);
            // Written where it is on, and under "auto" (whose default is on): the
            // other scenes read as they did before the key.
            let auto = f.method == super::FreeMethod::Auto;
            if let (Value::Table(m), true) = (&mut ft, f.reweigh || auto) {
                m.insert("reweigh".into(), value(f.reweigh));
            }
            t.insert("free_space".into(), ft);
        }
        if let Some(b) = self.periodic {
            let mut bt = table([
                ("method", value(b.method)),
                ("tolerance", value(b.tolerance)),
            ]);
            // A suspension's box is its own: the generator sets the size.
            if let (Value::Table(m), None) = (&mut bt, self.suspension) {
                m.insert("size".into(), value(b.size));
            }
            t.insert("box".into(), bt);
        }
        match (&self.helix, &self.suspension, self.cloud) {
            (_, _, Some(c)) => {
                t.insert(
                    "cloud".into(),
                    table([
                        ("count", value(c.count as i64)),
                        ("cloud_radius", value(c.cloud_radius)),
                        ("radius", value(c.radius)),
                        ("polydispersity", value(c.polydispersity)),
                        ("density", value(c.density)),
                        ("centre", value(c.centre)),
                        ("seed", value(c.seed as i64)),
                    ]),
                );
            }
            (_, Some(s), None) => {
                t.insert(
                    "suspension".into(),
                    table([
                        ("count", value(s.count as i64)),
                        ("fraction", value(s.fraction)),
                        ("radius", value(s.radius)),
                        ("polydispersity", value(s.polydispersity)),
                        ("density", value(s.density)),
                        ("seed", value(s.seed as i64)),
                    ]),
                );
                if let Some(f) = self.floor {
                    t.insert(
                        "floor".into(),
                        table([("radius", value(f.radius)), ("density", value(f.density))]),
                    );
                }
            }
            (Some(h), None, None) => {
                t.insert(
                    "helix".into(),
                    table([
                        ("tails", value(h.tails as i64)),
                        ("head_ratio", value(h.head_ratio)),
                        ("dhat", value(h.dhat)),
                        ("head_end", value(h.head_end)),
                        ("radius", value(h.radius)),
                        ("pitch", value(h.pitch)),
                        ("density", value(h.density)),
                    ]),
                );
            }
            (None, None, None) => {
                let particles = self.particles.iter().zip(&self.species).enumerate();
                let particles = particles.map(|(k, (p, s))| {
                    let mut pt = table([
                        ("position", value(p.position)),
                        ("radius", value(p.radius)),
                        ("density", value(p.density)),
                        ("velocity", value(p.velocity)),
                        ("angular_velocity", value(p.angular_velocity)),
                        ("species", value(s)),
                    ]);
                    if let (Value::Table(m), true) = (&mut pt, self.pinned.contains(&k)) {
                        m.insert("fixed".into(), value(true));
                    }
                    pt
                });
                t.insert("particle".into(), Value::Array(particles.collect()));
                let bonds = self.bonds.iter().map(|b| {
                    table([
                        ("between", value([b.i as i64, b.j as i64])),
                        ("length", value(b.length)),
                    ])
                });
                t.insert("bond".into(), Value::Array(bonds.collect()));
            }
        }
        format!(
            "# The resolved scene of this run: every default and `auto` choice written out.\n\n{}",
            toml::to_string(&t).expect("a table serializes")
        )
    }
}
