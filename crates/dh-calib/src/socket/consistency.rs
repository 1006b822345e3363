//! The contacts of a split and how consistent they are: each socket's modelled contact
//! points, their means, the distances to them (metres) and [`consistency`], and the noise
//! estimate of a fit.

use super::*;
use std::collections::BTreeMap;

/// Contacts of one split with their own socket numbering.
#[derive(Clone, Debug, Default)]
pub(super) struct Split2 {
    pub(super) contacts: Vec<Contact>,
    pub(super) names: Vec<String>,
    pub(super) constraints: Vec<SocketConstraint>,
}

pub(super) fn contacts_of(
    data: &Measurements,
    observed: &[Observed],
    split: Split,
) -> Result<Split2, CalibError> {
    let mut out = Split2::default();
    let mut index: HashMap<String, usize> = HashMap::new();
    // (partner name, distance, sigma, line) as first declared for each socket.
    let mut declared: Vec<Option<(String, f64, f64, usize)>> = Vec::new();
    let samples = data.samples.iter().filter(|s| s.split == split);
    for (s, o) in samples.zip(observed) {
        let Some(socket) = &s.socket else {
            return Err(CalibError::BadOption {
                what: format!("sample at line {}", s.line),
                reason: "expected a contact (a socket) in a set of contacts, found a measured \
                         point; contact and point samples cannot be mixed yet"
                    .into(),
            });
        };
        let next = out.names.len();
        let k = *index.entry(socket.name.clone()).or_insert(next);
        if k == next {
            out.names.push(socket.name.clone());
            declared.push(None);
        }
        if let Some(p) = &socket.partner {
            let this = (p.socket.clone(), p.distance, p.sigma, s.line);
            match &declared[k] {
                None => declared[k] = Some(this),
                Some((name, d, sd, line))
                    if name != &p.socket || *d != p.distance || *sd != p.sigma =>
                {
                    return Err(CalibError::BadOption {
                        what: format!("socket '{}' at line {}", socket.name, s.line),
                        reason: format!(
                            "expected the partner given at line {line} ('{name}' at {d} m ± {sd} \
                             m), found '{}' at {} m ± {} m",
                            p.socket, p.distance, p.sigma
                        ),
                    });
                }
                Some(_) => {}
            }
        }
        out.contacts.push(Contact {
            q: o.q.to_vec(),
            target: s.target,
            socket: k,
        });
    }
    for (a, d) in declared.iter().enumerate() {
        let Some((partner, distance, sigma, line)) = d else {
            continue;
        };
        let Some(&b) = index.get(partner) else {
            return Err(CalibError::BadOption {
                what: format!("socket '{}' at line {line}", out.names[a]),
                reason: format!("expected a partner socket of the same split, found '{partner}'"),
            });
        };
        let dup = out
            .constraints
            .iter()
            .any(|k| (k.a, k.b) == (b, a) || (k.a, k.b) == (a, b));
        if !dup && a != b {
            out.constraints.push(SocketConstraint {
                a,
                b,
                distance: *distance,
                sigma: *sigma,
            });
        }
    }
    Ok(out)
}

/// Distances of `part`'s contacts to their socket's modelled mean at `x` (metres).
pub(super) fn distances_to_means(model: &Model, x: &[f64], part: &Split2) -> Vec<f64> {
    let points = positions(model, x, &part.contacts);
    let m = means(&points, &part.contacts, part.names.len());
    points
        .iter()
        .zip(&part.contacts)
        .map(|(p, c)| (p - m[c.socket].0).norm())
        .collect()
}

/// Modelled positions of the contacts at `x` (device frame, metres).
pub(super) fn positions(model: &Model, x: &[f64], contacts: &[Contact]) -> Vec<Vector3<f64>> {
    contacts
        .iter()
        .map(|c| model.point(x, &c.q, c.target))
        .collect()
}

/// Per socket: the mean of its modelled positions and its sample count.
pub(super) fn means(
    points: &[Vector3<f64>],
    contacts: &[Contact],
    sockets: usize,
) -> Vec<(Vector3<f64>, usize)> {
    let mut m = vec![(Vector3::zeros(), 0usize); sockets];
    for (p, c) in points.iter().zip(contacts) {
        if let Some(e) = m.get_mut(c.socket) {
            e.0 += p;
            e.1 += 1;
        }
    }
    for e in &mut m {
        if e.1 > 0 {
            e.0 /= e.1 as f64;
        }
    }
    m
}

/// The consistency of `contacts` under the model at `x` (see the module docs); `None` without
/// contacts.
pub fn consistency(
    model: &Model,
    x: &[f64],
    contacts: &[Contact],
    constraints: &[SocketConstraint],
    sockets: usize,
) -> Option<Consistency> {
    if contacts.is_empty() {
        return None;
    }
    let points = positions(model, x, contacts);
    let mean = means(&points, contacts, sockets);
    // Placements: sockets linked by distances (union-find).
    let mut parent: Vec<usize> = (0..sockets).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for k in constraints {
        if k.a < sockets && k.b < sockets {
            let (ra, rb) = (root(&mut parent, k.a), root(&mut parent, k.b));
            parent[ra] = rb;
        }
    }
    // Ordered by socket: the mean of the means is summed in the same order in every process.
    let mut per: BTreeMap<usize, (f64, usize)> = BTreeMap::new();
    let mut all = Vec::with_capacity(points.len());
    for (p, c) in points.iter().zip(contacts) {
        let d = (p - mean[c.socket].0).norm();
        all.push(d);
        let e = per.entry(root(&mut parent, c.socket)).or_insert((0.0, 0));
        e.0 += d;
        e.1 += 1;
    }
    let stats = Stats::of(&all)?;
    let mean_abs = per.values().map(|(s, n)| s / *n as f64).sum::<f64>() / per.len() as f64;
    let distance_error = (!constraints.is_empty()).then(|| {
        constraints
            .iter()
            .map(|k| ((mean[k.a].0 - mean[k.b].0).norm() - k.distance).abs())
            .sum::<f64>()
            / constraints.len() as f64
    });
    Some(Consistency {
        mean_abs,
        rms: stats.rms,
        max: stats.max,
        distance_error,
        placements: per.len(),
        points: all.len(),
    })
}

/// Contact noise per axis from the contact residuals at `x` with `p` free parameters.
pub(super) fn sigma_of(problem: &SocketProblem<'_>, x: &[f64], p: usize) -> f64 {
    let mut r = [0.0; 3];
    let mut ss = 0.0;
    for b in 0..problem.contacts.len() {
        problem.residuals(x, b, &mut r);
        ss += r.iter().map(|v| v * v).sum::<f64>();
    }
    let dof = (3 * problem.contacts.len()).saturating_sub(p).max(1);
    (ss / dof as f64).sqrt().max(MIN_SIGMA)
}
