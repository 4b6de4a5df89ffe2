//! The bodies of a scene, from the raw form: the particles (or the paper's helix) with
//! their species, and the bonds, each checked and each error placed at the value at
//! fault; then the geometry (overlap, nesting) of the whole.

use std::ops::Range;

use toml::Spanned;

use hydrorattle::glam::DVec3;

use super::error::{Issue, issue};
use super::raw::{Bound, RawBond, RawHelix, RawParticle, distance, finite_vector, number, vector};
use super::resolve::BodySpans;
use super::{Bond, DEFAULT_DENSITY, Helix, Integrator, Method, Overlap, Particle};

pub(super) fn resolve_helix(r: &RawHelix) -> Result<Helix, Issue> {
    let d = Helix::default();
    let tails = match &r.tails {
        None => d.tails,
        Some(t) if *t.get_ref() == 0 => return Err(issue(t.span(), "tails must be >= 1")),
        Some(t) => *t.get_ref(),
    };
    Ok(Helix {
        tails,
        head_ratio: number(&r.head_ratio, d.head_ratio, "head_ratio", Bound::Positive)?,
        dhat: number(&r.dhat, d.dhat, "dhat", Bound::Positive)?,
        head_end: r.head_end.unwrap_or_default(),
        radius: number(&r.radius, d.radius, "helix radius", Bound::Positive)?,
        pitch: number(&r.pitch, d.pitch, "pitch", Bound::NonNegative)?,
        density: number(&r.density, d.density, "density", Bound::NonNegative)?,
    })
}

pub(super) type ParticleSpans = Vec<(Range<usize>, Range<usize>)>;

pub(super) fn resolve_particles(
    ps: &Spanned<Vec<RawParticle>>,
) -> Result<(Vec<Particle>, ParticleSpans, Vec<String>), Issue> {
    if ps.get_ref().is_empty() {
        return Err(issue(ps.span(), "the scene has no particles"));
    }
    let mut particles = Vec::with_capacity(ps.get_ref().len());
    let mut spans = Vec::with_capacity(ps.get_ref().len());
    let mut given = Vec::with_capacity(ps.get_ref().len());
    for p in ps.get_ref() {
        let position = finite_vector(&p.position, "position")?;
        let radius = number(&Some(p.radius.clone()), 0.0, "radius", Bound::Positive)?;
        let density = number(&p.density, DEFAULT_DENSITY, "density", Bound::NonNegative)?;
        let velocity = vector(&p.velocity, [0.0; 3], "velocity")?;
        let angular_velocity = vector(&p.angular_velocity, [0.0; 3], "angular_velocity")?;
        particles.push(Particle {
            position,
            radius,
            density,
            velocity,
            angular_velocity,
        });
        let dspan = p.density.as_ref().map_or(p.position.span(), |d| d.span());
        spans.push((p.position.span(), dspan));
        given.push(match &p.species {
            Some(name) => Some(species_name(name)?),
            None => None,
        });
    }
    let species = default_species(&particles, given);
    Ok((particles, spans, species))
}

/// A `species` name: 1 to 32 characters, letters, digits, `_`, `-`, `+` or `.`, so that
/// every trajectory format and viewer takes it as it is.
fn species_name(name: &Spanned<String>) -> Result<String, Issue> {
    let s = name.get_ref();
    let ok = (1..=32).contains(&s.len())
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-+.".contains(c));
    if ok {
        Ok(s.clone())
    } else {
        Err(issue(
            name.span(),
            format!("species {s:?} must be 1 to 32 letters, digits, '_', '-', '+' or '.'"),
        ))
    }
}

/// Species of explicit particles: the name given, or one name per distinct (radius,
/// density), `A`, `B`, ... in order of first appearance.
fn default_species(particles: &[Particle], given: Vec<Option<String>>) -> Vec<String> {
    let mut classes: Vec<(u64, u64)> = Vec::new();
    particles
        .iter()
        .zip(given)
        .map(|(p, name)| {
            name.unwrap_or_else(|| {
                let key = (p.radius.to_bits(), p.density.to_bits());
                let k = classes.iter().position(|c| *c == key).unwrap_or_else(|| {
                    classes.push(key);
                    classes.len() - 1
                });
                class_name(k)
            })
        })
        .collect()
}

fn class_name(k: usize) -> String {
    match u8::try_from(k) {
        Ok(k) if k < 26 => char::from(b'A' + k).to_string(),
        _ => format!("T{k}"),
    }
}

/// The bonds: a length of 0 only for springs (their rest length), and with FENE
/// springs every bond starts shorter than the maximum extension.
pub(super) fn resolve_bonds(
    bonds: Option<&Spanned<Vec<RawBond>>>,
    particles: &[Particle],
    integrator: &Integrator,
) -> Result<(Vec<Bond>, Vec<Range<usize>>), Issue> {
    let springs = integrator.method == Method::Springs;
    let Some(bonds) = bonds else {
        return Ok((Vec::new(), Vec::new()));
    };
    let n = particles.len();
    let mut out: Vec<Bond> = Vec::with_capacity(bonds.get_ref().len());
    let mut spans = Vec::with_capacity(bonds.get_ref().len());
    for b in bonds.get_ref() {
        let [i, j] = *b.between.get_ref();
        if i >= n || j >= n {
            return Err(issue(
                b.between.span(),
                format!(
                    "bond between [{i}, {j}]: particle index out of range (the scene has {n} particles, indices 0..={})",
                    n - 1
                ),
            ));
        }
        if i == j {
            return Err(issue(
                b.between.span(),
                format!("bond between [{i}, {j}] joins a particle to itself"),
            ));
        }
        if out
            .iter()
            .any(|o| (o.i == i && o.j == j) || (o.i == j && o.j == i))
        {
            return Err(issue(
                b.between.span(),
                format!("bond between [{i}, {j}] is given twice"),
            ));
        }
        let initial = distance(particles[i].position, particles[j].position);
        let bound = if springs {
            Bound::NonNegative
        } else {
            Bound::Positive
        };
        let length =
            number(&b.length, initial, "bond length", bound).map_err(|e| match &b.length {
                Some(l) if *l.get_ref() == 0.0 => issue(
                    l.span(),
                    "bond length must be > 0 (a rest length of 0 is for method = \"springs\" only)",
                ),
                _ => e,
            })?;
        if let Some(q0) = integrator.fene.filter(|&q0| initial >= q0) {
            return Err(issue(
                b.between.span(),
                format!(
                    "bond between [{i}, {j}] starts at distance {initial}, not below the FENE maximum extension {q0}"
                ),
            ));
        }
        out.push(Bond { i, j, length });
        spans.push(b.length.as_ref().map_or(b.between.span(), |l| l.span()));
    }
    Ok((out, spans))
}

/// Refuses nested spheres, and overlapping ones unless `overlap` allows them, at the
/// later sphere; in a periodic box through the minimum image. The pairs come from the
/// kernel's cell list (`O(N)` of them; the first in the order "later sphere, then
/// earlier", as the all-pairs loop meets them).
pub(super) fn check_geometry(
    particles: &[Particle],
    overlap: Overlap,
    periodic: Option<&super::PeriodicBox>,
    spans: &BodySpans,
) -> Result<(), Issue> {
    use hydrorattle::cell_list::{PairOrder, first_pair, indices};
    let cell = periodic.and_then(super::PeriodicBox::kernel);
    let sep = |i: usize, j: usize| {
        let (p, q) = (&particles[i], &particles[j]);
        match cell {
            None => distance(p.position, q.position),
            Some(c) => {
                let d = DVec3::from(q.position) - DVec3::from(p.position);
                c.minimum_image(d).length()
            }
        }
    };
    let nested =
        |i: usize, j: usize, s: f64| s <= (particles[i].radius - particles[j].radius).abs();
    let overlaps = |i: usize, j: usize, s: f64| {
        overlap == Overlap::Reject && s < particles[i].radius + particles[j].radius
    };
    let pos: Vec<DVec3> = particles.iter().map(|p| DVec3::from(p.position)).collect();
    // Either test needs `s <= |a_i| + |a_j|`.
    let reach = 2.0
        * particles
            .iter()
            .fold(0.0, |m: f64, p| m.max(p.radius.abs()));
    let mut store = vec![0; indices(particles.len())];
    let order = PairOrder::LaterFirst;
    let found = first_pair(&pos, cell.as_ref(), reach, order, &mut store, |i, j| {
        let s = sep(i, j);
        nested(i, j, s) || overlaps(i, j, s)
    });
    let Some((i, j)) = found else {
        return Ok(());
    };
    let (p, q, s) = (&particles[i], &particles[j], sep(i, j));
    let message = match nested(i, j, s) {
        true => format!(
            "particle {j} and particle {i} are nested (centre distance {s}, radii {} and {}): one sphere inside another is not a valid configuration",
            q.radius, p.radius
        ),
        false => format!(
            "particle {j} overlaps particle {i} at t = 0 (centre distance {s} < {}); if that is meant, say so with [model] overlap = \"allow\"",
            p.radius + q.radius
        ),
    };
    Err(issue(spans.position(j), message))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{BoxMethod, PeriodicBox};

    /// Random configurations (dilute to crowded, nested spheres planted in some), in
    /// free space and in a box: the cell list's verdict is the all-pairs loop's (written
    /// here: the first pair by later sphere, then earlier), the same pair and message.
    #[test]
    fn geometry_check_agrees_with_every_pair() {
        let mut g = hydrorattle::Noise::new(3);
        let (mut refused, mut passed) = (0, 0);
        for case in 0..60 {
            let n = [70, 150][case % 2];
            let spread = [6.0, 12.0, 25.0][case % 3];
            let mut particles: Vec<Particle> = (0..n)
                .map(|_| Particle {
                    position: [0; 3].map(|_| g.uniform() * spread),
                    radius: 0.2 + g.uniform(),
                    ..Particle::default()
                })
                .collect();
            if case % 4 == 1 {
                particles[n - 2].position = particles[3].position;
                particles[n - 2].position[0] += 0.05;
                (particles[3].radius, particles[n - 2].radius) = (1.2, 0.3);
            }
            let boxed = PeriodicBox {
                size: [spread, spread * 0.8, spread * 1.3],
                method: BoxMethod::Ewald,
                tolerance: 1e-6,
                method_line: None,
            };
            let cell = boxed.kernel();
            let spans = BodySpans::Helix(case..case + 1);
            for periodic in [None, Some(&boxed)] {
                for overlap in [Overlap::Reject, Overlap::Allow] {
                    let sep = |p: &Particle, q: &Particle| match periodic.and(cell) {
                        None => distance(p.position, q.position),
                        Some(c) => c
                            .minimum_image(DVec3::from(q.position) - DVec3::from(p.position))
                            .length(),
                    };
                    let want = (0..n)
                        .flat_map(|j| (0..j).map(move |i| (i, j)))
                        .find(|&(i, j)| {
                            let (p, q) = (&particles[i], &particles[j]);
                            let s = sep(p, q);
                            s <= (p.radius - q.radius).abs()
                                || (overlap == Overlap::Reject && s < p.radius + q.radius)
                        });
                    let got = check_geometry(&particles, overlap, periodic, &spans);
                    match (want, got) {
                        (None, Ok(())) => passed += 1,
                        (Some((i, j)), Err(e)) => {
                            let names = format!("particle {j} ");
                            let m = &e.message;
                            assert!(m.starts_with(&names), "{m} vs {i}, {j}");
                            assert!(m.contains(&format!("particle {i} ")), "{m}");
                            refused += 1;
                        }
                        (w, r) => panic!("case {case}: {w:?} vs {:?}", r.err().map(|e| e.message)),
                    }
                }
            }
        }
        assert!(refused > 40 && passed > 20, "{refused} / {passed}");
    }
}
