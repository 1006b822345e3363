//! Gravity torques on the joints of a DH chain or tree, from the masses its joints carry.
//!
//! # Inputs
//! [`Inertials`] give, per joint, the mass (kg) and centre of mass of the body that joint
//! moves (everything rigidly attached to the row's DH frame up to the next joint), expressed in
//! that row's DH frame: frame `i` of the table in both conventions, i.e. the frame after the
//! row's transform (see [`crate::tree::DhTree::frames`]); and per chain an optional payload
//! (mass and centre in the chain's tip frame, the table's tool applied). This crate never reads
//! a URDF: `urdf_axes::inertia` computes such composites from a URDF's `<inertial>` elements.
//!
//! # Torques
//! With `g` the gravity vector in the robot's base link frame (default `(0, 0, -9.80665)`: the
//! base link's `-z` is down), the torque of gravity about joint `i`'s axis (point `o_i`,
//! direction `z_i`) is
//!
//! ```text
//! tau_i = z_i · Σ_k (p_k − o_i) × (m_k g)
//! ```
//!
//! over every body `k` that joint `i` carries (its own and everything after it in the tree,
//! payloads included). Positive `tau_i` turns the joint in its positive sense, so a joint of
//! compliance `c` (rad/(N m)) sags by `c · tau_i` (J. L. Caenen, J. C. Angé, "Identification of
//! geometric and nongeometric parameters of robots", IEEE ICRA 1990; the same sum is used by
//! Tenhumberg & Bäuml 2021 for Agile Justin). For a prismatic joint it is the force along the
//! axis, `z_i · Σ m_k g` (N). The *lateral* torque of a row is the same sum about the `x` axis
//! that carries the row's `alpha` (the frame after the row in the standard convention, the
//! frame before it in the modified one), which bends the link about its twist axis.

use std::collections::HashMap;

use dh_core::{DhTable, JointKind, JointSampler};
use nalgebra::{Isometry3, Point3, Vector3};

use crate::fit::CalibError;
use crate::tree::{DhTree, TreeFrames};

/// Standard gravity (m/s²), ISO 80000-3.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// A mass and its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertial {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass (metres) in the frame named by the context.
    pub com: Vector3<f64>,
}

/// Link masses of a chain or tree (see the module docs for frames).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Inertials {
    /// `(joint name, body it moves)`, centre in the row's DH frame. Joints not listed carry
    /// no mass of their own.
    pub links: Vec<(String, Inertial)>,
    /// `(chain, payload)`, centre in the chain's tip frame; chain 0 for a serial robot, else
    /// the branch index.
    pub payloads: Vec<(usize, Inertial)>,
}

impl Inertials {
    /// Link masses given with their centres in the base link frame at the zero pose (every
    /// joint value 0), converted to the rows' DH frames of `tree`: the form in which a
    /// vendor's or an estimate's figures are easiest to write. `links` is
    /// `(joint, mass kg, centre m)`; `payloads` keep their tip-frame centres.
    ///
    /// # Errors
    /// [`CalibError::BadOption`] for a joint the tree does not have.
    pub fn from_zero_pose(
        tree: &DhTree,
        links: &[(String, f64, Vector3<f64>)],
        payloads: Vec<(usize, Inertial)>,
    ) -> Result<Inertials, CalibError> {
        let frames = tree.frames(&vec![0.0; tree.rows().len()])?;
        let links = links
            .iter()
            .map(|(name, mass, com)| {
                let r = tree
                    .row_index(name)
                    .ok_or_else(|| bad(format!("expected a joint of the model, found '{name}'")))?;
                let local = frames.after[r].inverse_transform_point(&Point3::from(*com));
                Ok((
                    name.clone(),
                    Inertial {
                        mass: *mass,
                        com: local.coords,
                    },
                ))
            })
            .collect::<Result<Vec<_>, CalibError>>()?;
        Ok(Inertials { links, payloads })
    }
}

/// Which axis a torque is taken about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TorqueAxis {
    /// The joint's own axis (or force along a prismatic axis).
    Joint,
    /// The `x` axis that carries the row's `alpha` (see the module docs).
    Lateral,
}

/// Gravity torques of a tree at its nominal geometry (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GravityModel {
    tree: DhTree,
    links: Vec<Option<Inertial>>,
    payloads: Vec<(usize, Inertial)>,
    gravity: Vector3<f64>,
    scales: Vec<[f64; 2]>,
    /// Per row, what it carries: the rows `k` it is an ancestor of that have a mass, and the
    /// payloads on a chain through it (indices into `payloads`). Built once: the torque asks
    /// for them at every sample.
    carried: Vec<(Vec<usize>, Vec<usize>)>,
    /// Identifies this model's geometry in the per-thread cache of frames ([`FRAMES`]).
    id: ModelId,
}

/// A number given to each [`GravityModel`] when it is built (its clones share it: they hold
/// the same geometry); it takes no part in equality.
#[derive(Clone, Copy, Debug)]
struct ModelId(u64);

impl PartialEq for ModelId {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl ModelId {
    fn next() -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        Self(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

/// The frames of one model at one set of joint values, and the torques asked for there so far
/// (per row, about [`TorqueAxis::Joint`] and [`TorqueAxis::Lateral`]; NaN until computed).
#[derive(Debug)]
struct AtJoints {
    frames: TreeFrames,
    torques: std::cell::RefCell<Vec<[f64; 2]>>,
}

/// The frames and torques known on one thread: the last joint values asked for (compared
/// first: every gravity effect of a calibration asks for the same sample's torques in turn,
/// for its change and again for its gradient), and those of up to [`FRAMES_KEPT`] joint values
/// by model id and the bits of the values (a fit asks for every sample's at each iteration, and
/// the frames are most of the work).
#[derive(Default)]
struct FrameCache {
    /// The model's id, the bits of the joint values, what is known there.
    last: Option<(u64, Vec<u64>, std::rc::Rc<AtJoints>)>,
    /// By the model's id followed by the bits of the joint values.
    kept: HashMap<Vec<u64>, std::rc::Rc<AtJoints>>,
    /// The key of the values asked for (reused).
    key: Vec<u64>,
}

/// Most joint values whose frames one thread keeps (about 3 KB each for a chain of 18 rows);
/// the cache is emptied when it is full.
const FRAMES_KEPT: usize = 2048;

thread_local! {
    /// This thread's [`FrameCache`].
    static FRAMES: std::cell::RefCell<FrameCache> = std::cell::RefCell::new(FrameCache::default());
}

fn bad(reason: String) -> CalibError {
    CalibError::BadOption {
        what: "inertials".into(),
        reason,
    }
}

impl GravityModel {
    /// Gravity along `-z` of the base link (`(0, 0, -9.80665)` m/s²).
    pub fn default_gravity() -> Vector3<f64> {
        Vector3::new(0.0, 0.0, -STANDARD_GRAVITY)
    }

    /// The gravity model of a serial table.
    ///
    /// # Errors
    /// As [`GravityModel::new`].
    pub fn serial(
        table: &DhTable,
        inertials: &Inertials,
        gravity: Vector3<f64>,
    ) -> Result<GravityModel, CalibError> {
        Self::new(&DhTree::serial(table), inertials, gravity)
    }

    /// The gravity model of `tree` with `inertials` under `gravity` (m/s², base link frame).
    ///
    /// # Errors
    /// [`CalibError::BadOption`] for a link naming no joint of the tree, a joint listed twice,
    /// a payload on a chain the tree does not have, a negative or non-finite mass or centre,
    /// or a non-finite gravity vector.
    pub fn new(
        tree: &DhTree,
        inertials: &Inertials,
        gravity: Vector3<f64>,
    ) -> Result<GravityModel, CalibError> {
        if gravity.iter().any(|v| !v.is_finite()) {
            return Err(bad(format!(
                "expected a finite gravity vector, found {gravity:?}"
            )));
        }
        let check = |what: &str, i: &Inertial| {
            if !(i.mass.is_finite() && i.mass >= 0.0) || i.com.iter().any(|v| !v.is_finite()) {
                Err(bad(format!(
                    "{what}: expected a finite mass >= 0 and a finite centre, found mass {} centre {:?}",
                    i.mass, i.com
                )))
            } else {
                Ok(())
            }
        };
        let mut links = vec![None; tree.rows().len()];
        for (name, i) in &inertials.links {
            check(&format!("joint '{name}'"), i)?;
            let r = tree
                .row_index(name)
                .ok_or_else(|| bad(format!("expected a joint of the model, found '{name}'")))?;
            if links[r].is_some() {
                return Err(bad(format!("joint '{name}' is listed twice")));
            }
            links[r] = Some(*i);
        }
        for (c, i) in &inertials.payloads {
            check(&format!("payload of chain {c}"), i)?;
            if *c >= tree.chain_count() {
                return Err(bad(format!(
                    "payload: expected a chain index below {}, found {c}",
                    tree.chain_count()
                )));
            }
        }
        let mut g = GravityModel {
            tree: tree.clone(),
            links,
            payloads: inertials.payloads.clone(),
            gravity,
            scales: vec![],
            carried: vec![],
            id: ModelId::next(),
        };
        g.carried = (0..g.links.len())
            .map(|row| {
                let links = (0..g.links.len())
                    .filter(|&k| g.links[k].is_some() && g.tree.is_ancestor(row, k))
                    .collect();
                let payloads = (0..g.payloads.len())
                    .filter(|&p| g.chain_has(g.payloads[p].0, row))
                    .collect();
                (links, payloads)
            })
            .collect();
        g.scales = g.rms_torques(32);
        Ok(g)
    }

    /// The nominal tree's frames at `q` (and the torques known there), from this thread's
    /// cache when `q` was the last asked.
    fn frames_at(&self, q: &[f64]) -> Option<std::rc::Rc<AtJoints>> {
        FRAMES.with(|cache| {
            let mut cache = cache.borrow_mut();
            let cache = &mut *cache;
            let same = |bits: &[u64]| bits.iter().copied().eq(q.iter().map(|v| v.to_bits()));
            if let Some((id, last, frames)) = &cache.last {
                if *id == self.id.0 && same(last) {
                    return Some(frames.clone());
                }
            }
            cache.key.clear();
            cache.key.push(self.id.0);
            cache.key.extend(q.iter().map(|v| v.to_bits()));
            let frames = match cache.kept.get(&cache.key[..]) {
                Some(frames) => frames.clone(),
                None => {
                    let frames = std::rc::Rc::new(AtJoints {
                        frames: self.tree.frames(q).ok()?,
                        torques: std::cell::RefCell::new(vec![[f64::NAN; 2]; self.links.len()]),
                    });
                    if cache.kept.len() >= FRAMES_KEPT {
                        cache.kept.clear();
                    }
                    cache.kept.insert(cache.key.clone(), frames.clone());
                    frames
                }
            };
            cache.last = Some((self.id.0, cache.key[1..].to_vec(), frames.clone()));
            Some(frames)
        })
    }

    /// The tree the torques are computed on (the nominal geometry).
    pub fn tree(&self) -> &DhTree {
        &self.tree
    }

    /// The gravity vector (m/s², base link frame).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// The link masses this model was built from (centres in the rows' DH frames of
    /// [`GravityModel::tree`]): with the tree and [`GravityModel::gravity`], what rebuilds it.
    pub fn inertials(&self) -> Inertials {
        Inertials {
            links: self
                .links
                .iter()
                .zip(self.tree.rows())
                .filter_map(|(i, r)| i.map(|i| (r.name.clone(), i)))
                .collect(),
            payloads: self.payloads.clone(),
        }
    }

    /// Mass (kg) that joint `row` carries: its own body and everything after it.
    pub fn carried_mass(&self, row: usize) -> f64 {
        let links: f64 = (0..self.links.len())
            .filter(|&k| self.tree.is_ancestor(row, k))
            .filter_map(|k| self.links[k].map(|i| i.mass))
            .sum();
        let tips: f64 = self
            .payloads
            .iter()
            .filter(|(c, _)| self.chain_has(*c, row))
            .map(|(_, i)| i.mass)
            .sum();
        links + tips
    }

    fn chain_has(&self, chain: usize, row: usize) -> bool {
        self.tree.chain_rows(chain).contains(&row)
    }

    /// The torque (N m; N for a prismatic joint about [`TorqueAxis::Joint`]) of gravity on row
    /// `row` at joint values `q` (one per row of the tree); 0 for a row or `q` out of range.
    pub fn torque(&self, q: &[f64], row: usize, axis: TorqueAxis) -> f64 {
        let Some(at) = self.frames_at(q) else {
            return 0.0;
        };
        let Some(r) = self.tree.rows().get(row) else {
            return 0.0;
        };
        let slot = usize::from(axis == TorqueAxis::Lateral);
        let known = at.torques.borrow().get(row).map_or(f64::NAN, |t| t[slot]);
        if !known.is_nan() {
            return known;
        }
        let frames = &at.frames;
        let (origin, dir) = match axis {
            TorqueAxis::Joint => frames.axis(row, r),
            TorqueAxis::Lateral => {
                let f: &Isometry3<f64> = match frames.conventions[row] {
                    dh_core::Convention::Standard => &frames.after[row],
                    dh_core::Convention::Modified => &frames.before[row],
                };
                (f.translation.vector, f.rotation * Vector3::x())
            }
        };
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        let mut add = |p: Vector3<f64>, m: f64| {
            let f = self.gravity * m;
            force += f;
            moment += (p - origin).cross(&f);
        };
        let (links, payloads) = &self.carried[row];
        for &k in links {
            if let Some(i) = &self.links[k] {
                add((frames.after[k] * Point3::from(i.com)).coords, i.mass);
            }
        }
        for &p in payloads {
            let (c, i) = &self.payloads[p];
            if let Some(tip) = frames.tips.get(*c) {
                add((tip * Point3::from(i.com)).coords, i.mass);
            }
        }
        let torque = if axis == TorqueAxis::Joint && r.kind == JointKind::Prismatic {
            dir.dot(&force)
        } else {
            dir.dot(&moment)
        };
        if let Some(t) = at.torques.borrow_mut().get_mut(row) {
            t[slot] = torque;
        }
        torque
    }

    /// The gravity lever arm (metres) of the first chain's tip about row `row`'s axis at `q`,
    /// at the nominal geometry in the base link frame: `l = z · ((p − o) × ĝ)`, `o`, `z` a
    /// point of the axis and its unit direction, `p` the tip's origin (the table's tool
    /// applied) and `ĝ` the unit gravity direction (the torque, N m, of a weight of 1 N at
    /// the tip). 0 for a row or `q` out of range, or without gravity.
    pub fn lever(&self, q: &[f64], row: usize) -> f64 {
        let Some(at) = self.frames_at(q) else {
            return 0.0;
        };
        let (Some(r), Some(tip)) = (self.tree.rows().get(row), at.frames.tips.first()) else {
            return 0.0;
        };
        let norm = self.gravity.norm();
        if norm == 0.0 {
            return 0.0;
        }
        let (origin, z) = at.frames.axis(row, r);
        z.dot(&(tip.translation.vector - origin).cross(&(self.gravity / norm)))
    }

    /// Every row's torque about its joint axis at `q`.
    pub fn torques(&self, q: &[f64]) -> Vec<f64> {
        (0..self.tree.rows().len())
            .map(|r| self.torque(q, r, TorqueAxis::Joint))
            .collect()
    }

    /// A typical size of row `row`'s torque about `axis` (N m): its RMS over joint values
    /// drawn uniformly within the limits (fixed seed), at least 1e-9.
    pub fn torque_scale(&self, row: usize, axis: TorqueAxis) -> f64 {
        let k = usize::from(axis == TorqueAxis::Lateral);
        self.scales.get(row).map_or(1e-9, |s| s[k])
    }

    fn rms_torques(&self, samples: usize) -> Vec<[f64; 2]> {
        let n = self.tree.rows().len();
        let mut sampler = JointSampler::new(self.tree.rows(), self.tree.size(), 0x6a71);
        let mut sums = vec![[0.0; 2]; n];
        let mut q = Vec::new();
        for _ in 0..samples {
            sampler.next_into(&mut q);
            for (r, s) in sums.iter_mut().enumerate() {
                s[0] += self.torque(&q, r, TorqueAxis::Joint).powi(2);
                s[1] += self.torque(&q, r, TorqueAxis::Lateral).powi(2);
            }
        }
        sums.into_iter()
            .map(|s| s.map(|v| (v / samples as f64).sqrt().max(1e-9)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dh_core::{Convention, DhRow};
    use std::f64::consts::FRAC_PI_2;

    /// A planar 2R arm in a vertical plane: joint axes along base y... built as standard DH
    /// with joint 1 turned so that its axis is horizontal.
    fn planar() -> DhTable {
        DhTable {
            convention: Convention::Standard,
            // DH frame 0: z along base -y, so joint 1 turns the arm in the x-z plane.
            base: Isometry3::rotation(Vector3::x() * FRAC_PI_2),
            tool: Isometry3::identity(),
            rows: vec![
                DhRow::revolute("j1", 1.0, 0.0, 0.0, 0.0),
                DhRow::revolute("j2", 0.5, 0.0, 0.0, 0.0),
            ],
        }
    }

    #[test]
    fn a_planar_arm_has_the_hand_computed_torques() {
        let t = planar();
        let inertials = Inertials {
            links: vec![
                // Masses at mid-link: frame i sits at the link's far end, x back along it.
                (
                    "j1".into(),
                    Inertial {
                        mass: 2.0,
                        com: Vector3::new(-0.5, 0.0, 0.0),
                    },
                ),
                (
                    "j2".into(),
                    Inertial {
                        mass: 1.0,
                        com: Vector3::new(-0.25, 0.0, 0.0),
                    },
                ),
            ],
            payloads: vec![(
                0,
                Inertial {
                    mass: 3.0,
                    com: Vector3::zeros(),
                },
            )],
        };
        let g = GravityModel::serial(&t, &inertials, GravityModel::default_gravity()).unwrap();
        let gr = STANDARD_GRAVITY;
        // Stretched out horizontally: joint 1 z is base -y; the arm along +x; gravity -z.
        // Moment of a weight at +x about the -y axis: (x, 0, 0) × (0, 0, -m g) = (0, m g x, 0),
        // dotted with (0, -1, 0) = -m g x: gravity turns the arm in the negative sense.
        let tau = g.torques(&[0.0, 0.0]);
        let expect1 = -gr * (2.0 * 0.5 + 1.0 * 1.25 + 3.0 * 1.5);
        let expect2 = -gr * (1.0 * 0.25 + 3.0 * 0.5);
        assert!((tau[0] - expect1).abs() < 1e-9, "{tau:?} {expect1}");
        assert!((tau[1] - expect2).abs() < 1e-9, "{tau:?} {expect2}");
        // Hanging straight down (joint 1 at -90 degrees about -y turns +x to -z... ): no torque.
        let tau = g.torques(&[-FRAC_PI_2, 0.0]);
        assert!(tau[0].abs() < 1e-9 && tau[1].abs() < 1e-9, "{tau:?}");
        assert!((g.carried_mass(1) - 4.0).abs() < 1e-12);
        assert!(g.torque_scale(0, TorqueAxis::Joint) > 10.0);
    }

    #[test]
    fn bad_inertials_are_errors() {
        let t = planar();
        let one = |name: &str, mass: f64| Inertials {
            links: vec![(
                name.into(),
                Inertial {
                    mass,
                    com: Vector3::zeros(),
                },
            )],
            payloads: vec![],
        };
        let g = GravityModel::default_gravity();
        assert!(GravityModel::serial(&t, &one("nope", 1.0), g).is_err());
        assert!(GravityModel::serial(&t, &one("j1", -1.0), g).is_err());
        assert!(
            GravityModel::serial(&t, &one("j1", 1.0), Vector3::new(f64::NAN, 0.0, 0.0)).is_err()
        );
    }
}
