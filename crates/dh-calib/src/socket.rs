//! Calibration from contacts with unknown fixed points: a ball on the flange placed by hand in
//! the sockets of a tool on the table, many joint configurations per socket, no measuring
//! device (MUKCa: G. Franzese, M. Spahn, J. Ramirez et al., "MUKCa: Accurate and Affordable
//! Cobot Calibration Without External Measurement Devices", 2025; data and code at
//! github.com/platonics-delft/kinematics_calibration).
//!
//! # Measurement model
//! A contact sample (a [`Sample`](crate::data::Sample) with a [`Socket`](crate::data::Socket))
//! says that target `k` (the ball centre, in the tip frame) sat in socket `s`:
//!
//! ```text
//! r = T_device_base · FK(q) · t_k − s        (3 residuals, metres)
//! ```
//!
//! with `s` the socket's unknown centre, three more parameters per socket (`socket.<name>.x|y|z`,
//! metres, in the device frame). A known distance `L ± σ_L` between two sockets (the tool's
//! sockets are 50 mm apart) is one more residual,
//!
//! ```text
//! r = (‖s_a − s_b‖ − L) · σ_point / σ_L
//! ```
//!
//! weighted so that both kinds are in units of the contact noise `σ_point` (per axis, metres):
//! the `sigma` option when given, otherwise the RMS per coordinate of the contact residuals of
//! the fit itself (iterated: fit, re-estimate, refit, until it changes by less than
//! [`SIGMA_CHANGE`]). Without distances the scale of the whole robot is free (every length,
//! target and socket times `1 + ε` fits as well); one distance fixes it to `σ_L / L` relative.
//!
//! # Gauge freedom
//! There is no measuring device: moving the device frame and every socket by the same rigid
//! motion changes no residual, so `device.*` is never observable. The sockets are reported in
//! the device frame held at the robot's base link frame (`T_device_base = I`), and the
//! identifiability analysis fixes `device.*` (priority 0, with `base.*` and `tool.*`) naming the
//! socket coordinates as its aliases.
//!
//! # Steps
//! - `as given`: no fit; the nominal model with its targets, each socket at the mean of its
//!   points;
//! - `nominal`: the targets and sockets;
//! - `geometric`: every identifiable DH, base, tool and target parameter with the sockets;
//! - `effects`: with the given effects, when there are any;
//! - or, with [`diagnose_sockets`] in automatic mode, one `+<label>` step per effect the rule
//!   selects (see there).
//!
//! # Consistency
//! [`Consistency`] is the figure MUKCa publishes (its `evaluate_model`): per placement (a pair
//! of sockets linked by a distance, or a lone socket), the mean Euclidean distance of each
//! modelled ball position to the mean of its socket's modelled positions, weighted by the
//! sockets' sample counts; then the plain mean over placements. It needs no socket estimate, so
//! it is computed alike on calibration and validation samples (sockets of held-out placements
//! are never fitted).

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{DMatrix, Isometry3, Vector3};

use dh_core::DhTable;

use crate::calibrate::{prepare, CalibrationOptions, FixedParameter, ParameterEstimate, Stats};
use crate::data::{Measurements, Split};
use crate::diagnose::{
    bic, effect_context, paired_wilcoxon, CandidateReport, CandidateStatus, DiagnoseOptions,
    EffectSelection, Trial, ALIAS_SINE,
};
use crate::effects;
use crate::fit::{self, CalibError, FitOutcome, Problem, Termination};
use crate::model::{xyz_rpy, Block, Effect, Field, Model, Observation, Observed};
use crate::stats;
use crate::tree::DhTree;

/// The contact noise estimate is iterated until it changes by less than this fraction.
pub const SIGMA_CHANGE: f64 = 0.05;

/// Passes of the noise re-estimation per step (fit, re-weight, refit).
const SIGMA_PASSES: usize = 4;

/// Smallest contact noise used to weight a distance (metres, 0.1 µm): far below any hand-placed
/// ball, it only keeps the weight finite on noise-free data.
pub const MIN_SIGMA: f64 = 1e-7;

/// A contact sample: joint values in row order, the target and the socket index.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// One value per model row (radians or metres).
    pub q: Vec<f64>,
    /// Target index.
    pub target: usize,
    /// Socket index.
    pub socket: usize,
}

/// A known distance between two sockets.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketConstraint {
    /// First socket index.
    pub a: usize,
    /// Second socket index.
    pub b: usize,
    /// Centre-to-centre distance (metres).
    pub distance: f64,
    /// Its standard deviation (metres).
    pub sigma: f64,
}

/// The contact problem (see the module docs): the model's parameters, then three per socket.
#[derive(Clone, Copy, Debug)]
pub struct SocketProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// Contact samples.
    pub contacts: &'a [Contact],
    /// Known distances.
    pub constraints: &'a [SocketConstraint],
    /// Number of sockets.
    pub sockets: usize,
    /// The contact noise `σ_point` that weights the distances (metres).
    pub sigma_point: f64,
}

impl SocketProblem<'_> {
    /// Index of the first socket parameter (`socket 0 .x`).
    pub fn socket_offset(&self) -> usize {
        self.model.parameter_count()
    }

    /// Socket `s`'s centre at `x` (metres, device frame).
    pub fn socket_at(&self, x: &[f64], s: usize) -> Vector3<f64> {
        let o = self.socket_offset() + 3 * s;
        Vector3::new(
            x.get(o).copied().unwrap_or(0.0),
            x.get(o + 1).copied().unwrap_or(0.0),
            x.get(o + 2).copied().unwrap_or(0.0),
        )
    }

    fn observed(&self, x: &[f64], c: &Contact) -> Observed {
        Observed::new(
            c.q.clone(),
            Observation::Point {
                target: c.target,
                point: self.socket_at(x, c.socket),
            },
        )
    }

    fn weight(&self, k: &SocketConstraint) -> f64 {
        self.sigma_point / k.sigma
    }
}

impl Problem for SocketProblem<'_> {
    fn parameter_count(&self) -> usize {
        self.model.parameter_count() + 3 * self.sockets
    }
    fn block_count(&self) -> usize {
        self.contacts.len() + self.constraints.len()
    }
    fn block_size(&self, block: usize) -> usize {
        if block < self.contacts.len() {
            3
        } else {
            1
        }
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        if let Some(c) = self.contacts.get(block) {
            self.model.residuals(x, &self.observed(x, c), out);
        } else if let Some(k) = self.constraints.get(block - self.contacts.len()) {
            let d = self.socket_at(x, k.a) - self.socket_at(x, k.b);
            out[0] = (d.norm() - k.distance) * self.weight(k);
        }
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        let offset = self.socket_offset();
        let nc = columns.len();
        jacobian[..self.block_size(block) * nc].fill(0.0);
        // Socket columns: which socket and axis, or None for a model column.
        let socket_of = |c: usize| (c >= offset).then(|| ((c - offset) / 3, (c - offset) % 3));
        if let Some(c) = self.contacts.get(block) {
            let model_cols: Vec<usize> = columns.iter().copied().filter(|&c| c < offset).collect();
            let mut jm = vec![0.0; 3 * model_cols.len()];
            self.model
                .jacobian(x, &self.observed(x, c), &model_cols, residuals, &mut jm);
            let mut m = 0;
            for (k, &col) in columns.iter().enumerate() {
                match socket_of(col) {
                    None => {
                        for i in 0..3 {
                            jacobian[i * nc + k] = jm[i * model_cols.len() + m];
                        }
                        m += 1;
                    }
                    // r = p − s: ∂r/∂s = −I.
                    Some((s, axis)) if s == c.socket => jacobian[axis * nc + k] = -1.0,
                    Some(_) => {}
                }
            }
        } else if let Some(k) = self.constraints.get(block - self.contacts.len()) {
            let d = self.socket_at(x, k.a) - self.socket_at(x, k.b);
            let n = d.norm();
            let w = self.weight(k);
            residuals[0] = (n - k.distance) * w;
            // ∂‖d‖/∂s_a = d/‖d‖ = −∂‖d‖/∂s_b (zero at coincident sockets, a saddle).
            let u = if n > 0.0 { d / n } else { Vector3::zeros() };
            for (col, &c) in columns.iter().enumerate() {
                match socket_of(c) {
                    Some((s, axis)) if s == k.a => jacobian[col] += w * u[axis],
                    Some((s, axis)) if s == k.b => jacobian[col] -= w * u[axis],
                    _ => {}
                }
            }
        }
    }
}

/// The consistency figures of one set of contacts (see the module docs), metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Consistency {
    /// MUKCa's "mean absolute error": per placement the mean distance to the socket mean, then
    /// the mean over placements.
    pub mean_abs: f64,
    /// RMS distance to the socket mean over every point.
    pub rms: f64,
    /// Largest distance to the socket mean.
    pub max: f64,
    /// Mean over the distances of `|‖m_a − m_b‖ − L|` with `m` the socket means (MUKCa's
    /// "distortion"); `None` without distances.
    pub distance_error: Option<f64>,
    /// Number of placements.
    pub placements: usize,
    /// Number of points.
    pub points: usize,
}

/// Consistency before and after one step.
#[derive(Clone, Debug, PartialEq)]
pub struct ConsistencyStep {
    /// `as given`, `nominal`, `geometric` or `effects`.
    pub label: String,
    /// On the calibration contacts.
    pub train: Consistency,
    /// On the validation contacts, when there are any.
    pub test: Option<Consistency>,
}

/// A socket's estimated centre.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketEstimate {
    /// Its name.
    pub name: String,
    /// Centre in the device frame (the robot's base link frame, see the module docs), metres.
    pub position: Vector3<f64>,
    /// Standard errors per axis (metres), when the fit gives them.
    pub std_error: Option<Vector3<f64>>,
    /// Contact samples in it.
    pub samples: usize,
}

/// One fitted step.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketStep {
    /// `nominal`, `geometric` or `effects`.
    pub label: String,
    /// RMS distance of the calibration contacts to their fitted sockets (metres).
    pub rms: f64,
    /// Mean of those distances (metres).
    pub mean: f64,
    /// Largest (metres).
    pub max: f64,
    /// RMS distance of the validation contacts to their socket's modelled mean (metres).
    pub val_rms: Option<f64>,
    /// Number of free parameters (sockets included).
    pub free: usize,
    /// Solver iterations (last noise pass).
    pub iterations: usize,
    /// Why the solver stopped.
    pub termination: Termination,
}

/// One contact's distance to the mean of its socket's modelled positions (the consistency's
/// distance, see the module docs), metres.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactDistance {
    /// Index of the sample in the measurements.
    pub sample: usize,
    /// Whether it is a validation contact.
    pub validation: bool,
    /// Its socket's name.
    pub socket: String,
    /// With the model as given.
    pub as_given: f64,
    /// After the last step.
    pub last: f64,
}

/// The result of [`calibrate_sockets`]. Lengths in metres, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketReport {
    /// The fitted steps, in order.
    pub steps: Vec<SocketStep>,
    /// Every model parameter, then the socket coordinates (`socket.<name>.x|y|z`, nominal = the
    /// `as given` socket means).
    pub parameters: Vec<ParameterEstimate>,
    /// Parameters held at their start because the data cannot identify them, with aliases.
    pub fixed: Vec<FixedParameter>,
    /// The calibrated table, tilts in their rows' `beta` (see [`Model::table_at`]).
    pub calibrated: DhTable,
    /// Estimated target positions in the tip frame.
    pub targets: Vec<(String, Vector3<f64>)>,
    /// Condition number of the scaled Jacobian of the last step's free parameters.
    pub condition_number: f64,
    /// Residual standard deviation of the last fit (weighted residuals, metres).
    pub sigma_hat: Option<f64>,
    /// Remarks (gauge freedom, scale).
    pub notes: Vec<String>,
    /// Consistency per step, `as given` first.
    pub consistency: Vec<ConsistencyStep>,
    /// The calibration sockets.
    pub sockets: Vec<SocketEstimate>,
    /// The known distances between calibration sockets.
    pub constraints: Vec<SocketConstraint>,
    /// The contact noise that weighted the distances in the last step (metres per axis).
    pub sigma_point: f64,
    /// Labels of the effects estimated in the last step (declared, or selected by
    /// [`diagnose_sockets`]).
    pub selected_effects: Vec<String>,
    /// The candidate table of the first round of [`diagnose_sockets`] (empty otherwise), best
    /// score first. `val_rms` is the held-out RMS distance to the socket means after the full
    /// refit, for the candidates that were refitted (metres).
    pub candidates: Vec<CandidateReport>,
    /// Every full refit of a candidate, in order, with the tests of the rule.
    pub trials: Vec<Trial>,
    /// Every contact's distance to its socket's modelled mean, as given and after the last
    /// step, in the order of the measurements.
    pub distances: Vec<ContactDistance>,
}

/// Contacts of one split with their own socket numbering.
#[derive(Clone, Debug, Default)]
struct Split2 {
    contacts: Vec<Contact>,
    names: Vec<String>,
    constraints: Vec<SocketConstraint>,
}

fn contacts_of(
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
            q: o.q.clone(),
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
fn distances_to_means(model: &Model, x: &[f64], part: &Split2) -> Vec<f64> {
    let points = positions(model, x, &part.contacts);
    let m = means(&points, &part.contacts, part.names.len());
    points
        .iter()
        .zip(&part.contacts)
        .map(|(p, c)| (p - m[c.socket].0).norm())
        .collect()
}

/// Modelled positions of the contacts at `x` (device frame, metres).
fn positions(model: &Model, x: &[f64], contacts: &[Contact]) -> Vec<Vector3<f64>> {
    contacts
        .iter()
        .map(|c| model.point(x, &c.q, c.target))
        .collect()
}

/// Per socket: the mean of its modelled positions and its sample count.
fn means(
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
    let mut per: HashMap<usize, (f64, usize)> = HashMap::new();
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
fn sigma_of(problem: &SocketProblem<'_>, x: &[f64], p: usize) -> f64 {
    let mut r = [0.0; 3];
    let mut ss = 0.0;
    for b in 0..problem.contacts.len() {
        problem.residuals(x, b, &mut r);
        ss += r.iter().map(|v| v * v).sum::<f64>();
    }
    let dof = (3 * problem.contacts.len()).saturating_sub(p).max(1);
    (ss / dof as f64).sqrt().max(MIN_SIGMA)
}

/// Everything the steps share.
struct Run<'a> {
    model: Model,
    cal: Split2,
    val: Split2,
    scales: Vec<f64>,
    options: &'a CalibrationOptions,
    sigma_point: f64,
}

impl Run<'_> {
    fn problem(&self, sigma_point: f64) -> SocketProblem<'_> {
        SocketProblem {
            model: &self.model,
            contacts: &self.cal.contacts,
            constraints: &self.cal.constraints,
            sockets: self.cal.names.len(),
            sigma_point,
        }
    }

    /// Fits `free` from `x0`, re-estimating the contact noise that weights the distances.
    fn fit(&mut self, x0: &[f64], free: &[usize]) -> Result<FitOutcome, CalibError> {
        let mut x = x0.to_vec();
        let given = self.options.sigma;
        let mut sigma = match given {
            Some(s) => s,
            None => sigma_of(&self.problem(1.0), x0, free.len()),
        };
        let mut outcome = None;
        for _ in 0..SIGMA_PASSES {
            let problem = self.problem(sigma);
            let o = fit::solve(&problem, &x, free, &self.scales, &self.options.fit)?;
            x.clone_from(&o.x);
            outcome = Some(o);
            if given.is_some() {
                break;
            }
            let next = sigma_of(&problem, &x, free.len());
            let change = (next / sigma - 1.0).abs();
            sigma = next;
            if change < SIGMA_CHANGE {
                break;
            }
        }
        self.sigma_point = sigma;
        outcome.ok_or_else(|| CalibError::NoConvergence {
            what: "socket fit".into(),
        })
    }

    fn step(
        &mut self,
        label: &str,
        x0: &[f64],
        free: &[usize],
    ) -> Result<(FitOutcome, SocketStep), CalibError> {
        let outcome = self.fit(x0, free)?;
        let problem = self.problem(self.sigma_point);
        let d: Vec<f64> = positions(&self.model, &outcome.x, &self.cal.contacts)
            .iter()
            .zip(&self.cal.contacts)
            .map(|(p, c)| (p - problem.socket_at(&outcome.x, c.socket)).norm())
            .collect();
        let cal = Stats::of(&d).unwrap_or(Stats {
            rms: 0.0,
            mean: 0.0,
            max: 0.0,
            count: 0,
        });
        let val = self.held_out(&outcome.x);
        let report = SocketStep {
            label: label.into(),
            rms: cal.rms,
            mean: cal.mean,
            max: cal.max,
            val_rms: val.map(|v| v.rms),
            free: free.len(),
            iterations: outcome.iterations,
            termination: outcome.termination,
        };
        Ok((outcome, report))
    }

    /// Distances of the validation contacts to their socket's mean (metres).
    fn held_out_distances(&self, x: &[f64]) -> Vec<f64> {
        distances_to_means(&self.model, x, &self.val)
    }

    /// Their statistics, `None` without validation contacts.
    fn held_out(&self, x: &[f64]) -> Option<Stats> {
        Stats::of(&self.held_out_distances(x))
    }

    /// Scores the model's effect `e` at `x` with `free` estimated (see [`diagnose_sockets`]):
    /// the QR factor of the scaled columns `[free, effect]` gives the first-order SSR reduction
    /// (the effect's part of `Qᵀr`, m²) and the independence (smallest singular value of the
    /// effect's block of `R` over its largest column norm).
    fn score(&self, x: &[f64], free: &[usize], e: usize) -> Result<CandidateReport, CalibError> {
        let (label, cols): (String, Vec<usize>) = match self.model.effects().get(e) {
            Some((eff, r)) => (eff.label(), r.clone().collect()),
            None => (String::new(), Vec::new()),
        };
        let p = free.len();
        let k = cols.len();
        let mut columns = free.to_vec();
        columns.extend(&cols);
        let f = fit::factor(&self.problem(self.sigma_point), x, &columns, &self.scales)?;
        let big = (p..p + k).map(|j| f.r.column(j).norm()).fold(0.0, f64::max);
        let inert = k == 0 || big <= 0.0;
        let smin = if inert {
            0.0
        } else {
            f.r.view((p, p), (k, k))
                .clone_owned()
                .singular_values()
                .min()
        };
        let independence = if inert { 0.0 } else { smin / big };
        let aliased = !inert && independence < ALIAS_SINE;
        let reduction: f64 = (p..p + k).map(|i| f.qtr[i] * f.qtr[i]).sum();
        Ok(CandidateReport {
            label,
            parameters: k,
            score: if aliased || inert { 0.0 } else { reduction },
            independence,
            val_rms: None,
            reason: None,
            status: if inert {
                CandidateStatus::Inert
            } else if aliased {
                CandidateStatus::Aliased
            } else {
                CandidateStatus::NotSelected
            },
        })
    }

    fn consistency(&self, label: &str, x: &[f64]) -> Option<ConsistencyStep> {
        let c = &self.cal;
        let v = &self.val;
        Some(ConsistencyStep {
            label: label.into(),
            train: consistency(&self.model, x, &c.contacts, &c.constraints, c.names.len())?,
            test: consistency(&self.model, x, &v.contacts, &v.constraints, v.names.len()),
        })
    }

    /// Identifiability of `columns` at `x`: free and fixed (see [`fit::identifiability`]), with
    /// the device frame fixed first (gauge, see the module docs) and the sockets last.
    fn identify(
        &self,
        x: &[f64],
        columns: &[usize],
    ) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
        let problem = self.problem(self.sigma_point);
        let f = fit::factor(&problem, x, columns, &self.scales)?;
        let prio_model = self.model.priorities();
        let prio: Vec<u32> = columns
            .iter()
            .map(|&c| match self.model.parameters().get(c).map(|p| p.block) {
                Some(Block::Device) => 0,
                Some(_) => prio_model[c],
                None => 5,
            })
            .collect();
        let id = fit::identifiability(
            &f.r,
            &vec![1.0; columns.len()],
            &prio,
            self.options.fit.rank_tolerance,
        )?;
        let free = id.free.iter().map(|&i| columns[i]).collect();
        let fixed = id
            .fixed
            .into_iter()
            .map(|f| fit::Fixed {
                index: columns[f.index],
                aliases: f.aliases.iter().map(|&a| columns[a]).collect(),
                combination: Vec::new(),
            })
            .collect();
        Ok((free, fixed))
    }

    fn name_of(&self, c: usize) -> String {
        match self.model.parameters().get(c) {
            Some(p) => p.name.clone(),
            None => {
                let s = c - self.model.parameter_count();
                let axis = ["x", "y", "z"][s % 3];
                let name = self.cal.names.get(s / 3).map_or("?", String::as_str);
                format!("socket.{name}.{axis}")
            }
        }
    }
}

/// Calibrates `tree` from the contact samples of `data` (see the module docs): the samples for
/// calibration are fitted, those marked for validation (other placements, whose sockets are
/// never fitted) give the held-out figures. The effects of `options` are estimated in one
/// `effects` step after the geometric one. The device guess and the folds of `options` are not
/// used (there is no device, and validation is by split only).
///
/// # Errors
/// [`CalibError::BadOption`] for a set with measured points, a partner socket that is not in
/// the same split or a socket whose partner differs between samples;
/// [`CalibError::TooFewSamples`] with fewer than 3 calibration contacts; and the errors of
/// [`Model::new_tree`] and [`fit::solve`].
pub fn calibrate_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
) -> Result<SocketReport, CalibError> {
    run_sockets(tree, data, options, None)
}

/// [`calibrate_sockets`] with the effects chosen as [`crate::diagnose`] chooses them for
/// measured points, adapted to contacts (`diag.effects`: `None` stops after the geometric step,
/// `Labels` are all estimated in one `effects` step, `Auto` selects; `options.effects` is
/// ignored).
///
/// # Automatic selection
/// 1. **Anything left?** With a known contact noise (`options.sigma`, metres per axis) the
///    chi-square `SSR / σ²` of the geometric step on `m − p` degrees of freedom (`m` residuals:
///    three per contact and one per distance, `p` free parameters, sockets included); a test
///    that finds nothing left at `diag.alpha` selects nothing. Without it the noise is
///    estimated from the same residuals and there is no test (contacts have no repeated
///    measured points for a pure error).
/// 2. **Score**: for every candidate of [`effects::candidates`], the first-order reduction of
///    the SSR (m²) by its Jacobian columns beyond those of the estimated parameters (sockets
///    included), from the QR factor of `[J_free C]`: `‖(Qᵀr)_C‖²`; its independence is the
///    smallest singular value of the `C` block of `R` over the largest column norm of `C`;
///    below [`ALIAS_SINE`] it is aliased (a scale, when one distance is all that fixes the
///    scale, is aliased only with the distances' weight) and never selected.
/// 3. **Rule**: ranked by score minus `k σ̂² ln m`, the [`DiagnoseOptions::trials`] best are
///    refitted in full in turn; the first that passes (a) F-to-enter at `alpha / K`, (b) a lower
///    BIC (both with the distances weighted as before the refit) and (c) a one-sided Wilcoxon
///    signed-rank test at `alpha` of the squared distances of the held-out contacts to their
///    socket's modelled mean, paired per contact (skipped without held-out contacts), is added
///    as a step `+<label>`; the loop repeats, up to [`DiagnoseOptions::max_effects`].
///
/// # Errors
/// Those of [`calibrate_sockets`]; [`CalibError::BadOption`] for a bad `alpha`, label or
/// inertials.
pub fn diagnose_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    diag: &DiagnoseOptions,
) -> Result<SocketReport, CalibError> {
    let ctx = effect_context(tree, diag)?;
    let mut plain = options.clone();
    plain.effects.clear();
    match &diag.effects {
        EffectSelection::None => run_sockets(tree, data, &plain, None),
        EffectSelection::Labels(labels) => {
            for l in labels {
                let e = effects::parse_label_in(l, &ctx)?;
                if e.uses_sequence() {
                    return Err(CalibError::BadOption {
                        what: format!("effect '{l}'"),
                        reason: "expected an effect of the joint values, found one of the \
                                 sample order, which contact data does not carry"
                            .into(),
                    });
                }
                plain.effects.push(e);
            }
            run_sockets(tree, data, &plain, None)
        }
        EffectSelection::Auto => {
            let probe = Model::new_tree(tree, &[], &options.model)?;
            let c = effects::candidates(&ctx, &probe.tilt_rows());
            let mut skipped = c.skipped;
            skipped.push(
                "backlash_direction, drift: not searched on contacts (contact data carries no \
                 sample order); gear_harmonic2, gear_harmonic:J:2: not searched on contacts (the \
                 contact selection does not compare rival effects of one joint), name them with \
                 --effects"
                    .into(),
            );
            let pool = c
                .effects
                .into_iter()
                .filter(|e| {
                    let l = e.label();
                    let both_harmonics = l.starts_with("gear_harmonic:") && l.ends_with(":2");
                    !(e.uses_sequence() || l.starts_with("gear_harmonic2:") || both_harmonics)
                })
                .collect();
            let auto = Auto {
                pool,
                skipped,
                diag,
            };
            run_sockets(tree, data, &plain, Some(&auto))
        }
    }
}

/// The candidates of an automatic selection and its options.
struct Auto<'a> {
    pool: Vec<Arc<dyn Effect>>,
    skipped: Vec<String>,
    diag: &'a DiagnoseOptions,
}

/// What the automatic selection leaves.
struct Selection {
    selected: Vec<usize>,
    candidates: Vec<CandidateReport>,
    trials: Vec<Trial>,
    notes: Vec<String>,
}

fn run_sockets(
    tree: &DhTree,
    data: &Measurements,
    options: &CalibrationOptions,
    auto: Option<&Auto<'_>>,
) -> Result<SocketReport, CalibError> {
    if data.session_count() > 1 {
        return Err(CalibError::BadOption {
            what: "contact calibration".into(),
            reason: format!(
                "expected one measurement session (the socket model has one device frame), found {} ({})",
                data.session_count(),
                data.sessions.join(", ")
            ),
        });
    }
    let prep = prepare(tree, data, None)?;
    let cal = contacts_of(data, &prep.cal, Split::Calibration)?;
    let val = contacts_of(data, &prep.val, Split::Validation)?;
    if cal.contacts.len() < 3 {
        return Err(CalibError::TooFewSamples {
            what: "socket calibration".into(),
            needed: 3,
            found: cal.contacts.len(),
        });
    }
    let targets: Vec<(String, usize)> = data.targets.iter().map(|t| (t.clone(), 0)).collect();
    let mut model = Model::new_tree(tree, &targets, &options.model)?;
    for e in &options.effects {
        model.add_effect(Arc::clone(e))?;
    }
    // The candidates ride along at zero (outside every step's free set) until selected.
    for e in auto.map_or(&[][..], |a| &a.pool) {
        model.add_effect(Arc::clone(e))?;
    }
    if let Some(t) = &options.target_guesses {
        if t.len() != model.targets().len() {
            return Err(CalibError::Length {
                what: "target guesses".into(),
                expected: model.targets().len(),
                found: t.len(),
            });
        }
        for (k, v) in t.iter().enumerate() {
            model.set_target(k, *v);
        }
    }
    let n_model = model.parameter_count();
    let n_sockets = cal.names.len();
    let mut scales = model.scales();
    scales.extend(std::iter::repeat_n(1.0, 3 * n_sockets));
    let mut run = Run {
        model,
        cal,
        val,
        scales,
        options,
        sigma_point: MIN_SIGMA,
    };

    // As given: sockets at the means of their nominal points.
    let mut x = vec![0.0; n_model + 3 * n_sockets];
    let start = means(
        &positions(&run.model, &x, &run.cal.contacts),
        &run.cal.contacts,
        n_sockets,
    );
    for (s, (m, _)) in start.iter().enumerate() {
        x[n_model + 3 * s..n_model + 3 * s + 3].copy_from_slice(m.as_slice());
    }
    let sockets_given: Vec<Vector3<f64>> = start.iter().map(|m| m.0).collect();
    let x_given = x.clone();
    let mut consistency: Vec<ConsistencyStep> =
        run.consistency("as given", &x).into_iter().collect();

    let measured_target = |k: usize| run.cal.contacts.iter().any(|c| c.target == k);
    let targets_used: Vec<bool> = (0..run.model.targets().len())
        .map(measured_target)
        .collect();
    let socket_cols: Vec<usize> = (n_model..n_model + 3 * n_sockets).collect();
    let mut nominal_free = run
        .model
        .indices(|b| matches!(b, Block::Target(k) if targets_used[k]));
    nominal_free.extend(&socket_cols);
    let (out, report) = run.step("nominal", &x, &nominal_free)?;
    x = out.x;
    let targets_nominal: Vec<Vector3<f64>> = (0..run.model.targets().len())
        .map(|k| run.model.target_at(&x, k))
        .collect();
    let mut steps = vec![report];
    consistency.extend(run.consistency("nominal", &x));

    let mut geometric = run.model.indices(|b| {
        !matches!(b, Block::Effect(_)) && !matches!(b, Block::Target(k) if !targets_used[k])
    });
    geometric.extend(&socket_cols);
    let (free, mut fixed) = run.identify(&x, &geometric)?;
    let (mut last, report) = run.step("geometric", &x, &free)?;
    steps.push(report);
    consistency.extend(run.consistency("geometric", &last.x));

    let mut selection = None;
    if let Some(a) = auto {
        let mut state = Chosen {
            last,
            free,
            fixed,
            steps,
            consistency,
        };
        selection = Some(select(&mut run, a, &mut state)?);
        Chosen {
            last,
            fixed,
            steps,
            consistency,
            ..
        } = state;
    } else if !options.effects.is_empty() {
        let mut all: Vec<usize> = run
            .model
            .indices(|b| !matches!(b, Block::Target(k) if !targets_used[k]));
        all.extend(&socket_cols);
        let (free, fixed2) = run.identify(&last.x, &all)?;
        fixed = fixed2;
        let (o, report) = run.step("effects", &last.x, &free)?;
        last = o;
        steps.push(report);
        consistency.extend(run.consistency("effects", &last.x));
    }

    let x = last.x.clone();
    let problem = run.problem(run.sigma_point);
    let sockets: Vec<SocketEstimate> = (0..n_sockets)
        .map(|s| {
            let o = n_model + 3 * s;
            let se = |i: usize| last.std_errors.get(o + i).copied().flatten();
            SocketEstimate {
                name: run.cal.names[s].clone(),
                position: problem.socket_at(&x, s),
                std_error: match (se(0), se(1), se(2)) {
                    (Some(a), Some(b), Some(c)) => Some(Vector3::new(a, b, c)),
                    _ => None,
                },
                samples: run.cal.contacts.iter().filter(|c| c.socket == s).count(),
            }
        })
        .collect();
    // Candidates never selected are no parameters of the result.
    let unselected = |b: Block| match (b, &selection) {
        (Block::Effect(e), Some(sel)) => !sel.selected.contains(&e),
        _ => false,
    };
    let mut parameters: Vec<ParameterEstimate> = estimates(&run.model, &x, &last, &targets_nominal)
        .into_iter()
        .zip(run.model.parameters())
        .filter(|(_, p)| !unselected(p.block))
        .map(|(e, _)| e)
        .collect();
    for (s, est) in sockets.iter().enumerate() {
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            parameters.push(ParameterEstimate {
                name: format!("socket.{}.{name}", est.name),
                nominal: sockets_given[s][axis],
                estimate: est.position[axis],
                std_error: est.std_error.map(|v| v[axis]),
                free: last.free.contains(&(n_model + 3 * s + axis)),
            });
        }
    }
    let mut notes = vec![
        "the device frame is not observable from contacts with unknown sockets (gauge freedom): \
         it is held at the robot's base link frame and the sockets are in that frame"
            .to_string(),
    ];
    if run.cal.constraints.is_empty() {
        notes.push(
            "no distance between sockets is known: the scale of the robot is not observable".into(),
        );
    }
    let tree_at = run.model.tree_at(&x);
    let fixed: Vec<FixedParameter> = fixed
        .iter()
        .filter(|f| {
            !run.model
                .parameters()
                .get(f.index)
                .is_some_and(|p| unselected(p.block))
        })
        .map(|f| FixedParameter {
            name: run.name_of(f.index),
            aliases: f.aliases.iter().map(|&a| run.name_of(a)).collect(),
        })
        .collect();
    let effects = run.model.effects();
    let selected_effects: Vec<String> = match &selection {
        Some(sel) => sel
            .selected
            .iter()
            .filter_map(|&e| effects.get(e).map(|(eff, _)| eff.label()))
            .collect(),
        None => options.effects.iter().map(|e| e.label()).collect(),
    };
    let mut distances = Vec::with_capacity(data.samples.len());
    for (split, part) in [
        (Split::Calibration, &run.cal),
        (Split::Validation, &run.val),
    ] {
        let before = distances_to_means(&run.model, &x_given, part);
        let after = distances_to_means(&run.model, &x, part);
        let samples = data
            .samples
            .iter()
            .enumerate()
            .filter(|(_, s)| s.split == split);
        for (((i, _), c), (b, a)) in samples.zip(&part.contacts).zip(before.iter().zip(&after)) {
            distances.push(ContactDistance {
                sample: i,
                validation: split == Split::Validation,
                socket: part.names.get(c.socket).cloned().unwrap_or_default(),
                as_given: *b,
                last: *a,
            });
        }
    }
    distances.sort_by_key(|d| d.sample);
    let (candidates, trials) = match selection {
        Some(sel) => {
            notes.extend(sel.notes);
            (sel.candidates, sel.trials)
        }
        None => (Vec::new(), Vec::new()),
    };
    Ok(SocketReport {
        steps,
        parameters,
        fixed,
        calibrated: tree_at.trunk().clone(),
        targets: (0..run.model.targets().len())
            .map(|k| (run.model.targets()[k].0.clone(), run.model.target_at(&x, k)))
            .collect(),
        condition_number: last.condition_number,
        sigma_hat: last.sigma,
        notes,
        consistency,
        sockets,
        constraints: run.cal.constraints.clone(),
        sigma_point: run.sigma_point,
        selected_effects,
        candidates,
        trials,
        distances,
    })
}

/// The state the automatic selection advances: the last fit, its free and fixed parameters,
/// the steps and consistency figures so far.
struct Chosen {
    last: FitOutcome,
    free: Vec<usize>,
    fixed: Vec<fit::Fixed>,
    steps: Vec<SocketStep>,
    consistency: Vec<ConsistencyStep>,
}

/// The automatic selection of [`diagnose_sockets`] on the candidates of `auto` (the model's
/// effects, in the same order), from the geometric step in `state`.
fn select(run: &mut Run<'_>, auto: &Auto<'_>, state: &mut Chosen) -> Result<Selection, CalibError> {
    let diag = auto.diag;
    let mut out = Selection {
        selected: Vec::new(),
        candidates: Vec::new(),
        trials: Vec::new(),
        notes: auto.skipped.clone(),
    };
    if auto.pool.is_empty() {
        return Ok(out);
    }
    let residuals = 3 * run.cal.contacts.len() + run.cal.constraints.len();
    let m = residuals as f64;
    // Step 1: anything left?
    let mut proceed = true;
    match run.options.sigma {
        Some(sigma) => {
            let ssr = fit::sum_of_squares(&run.problem(sigma), &state.last.x).unwrap_or(f64::NAN);
            let chi2 = ssr / (sigma * sigma);
            let dof = (m - state.free.len() as f64).max(1.0);
            let p = stats::chi2_sf(chi2, dof);
            let summary = format!(
                "chi-square {chi2:.1} on {dof:.0} degrees of freedom against the given contact \
                 noise, p = {p:.2e}"
            );
            out.notes
                .push(format!("residual after the geometric step: {summary}"));
            if p >= diag.alpha {
                out.notes.push(
                    "nothing significant is left after the geometric step; no effect is selected"
                        .into(),
                );
                proceed = false;
            }
        }
        None => out.notes.push(
            "residual after the geometric step: no test (the contact noise is estimated from the \
             same residuals; give --sigma for a chi-square test)"
                .into(),
        ),
    }
    if run.val.contacts.is_empty() {
        out.notes.push(
            "no held-out contacts: the selection rests on the F-to-enter and BIC tests alone"
                .into(),
        );
    }
    let mut rejected: Vec<usize> = Vec::new();
    let mut first = true;
    loop {
        let remaining: Vec<usize> = (0..auto.pool.len())
            .filter(|e| !out.selected.contains(e))
            .collect();
        if remaining.is_empty() {
            break;
        }
        let mut table: Vec<(usize, CandidateReport)> = Vec::with_capacity(remaining.len());
        for &e in &remaining {
            table.push((e, run.score(&state.last.x, &state.free, e)?));
        }
        table.sort_by(|a, b| b.1.score.total_cmp(&a.1.score));
        if first {
            out.candidates = table.iter().map(|(_, c)| c.clone()).collect();
            first = false;
        }
        if !proceed {
            break;
        }
        if out.selected.len() >= diag.max_effects {
            out.notes.push(format!(
                "stopped after the most effects allowed ({}); candidates may remain",
                diag.max_effects
            ));
            break;
        }
        let sigma0 = run.sigma_point;
        let problem = run.problem(sigma0);
        let ssr0 = fit::sum_of_squares(&problem, &state.last.x).unwrap_or(f64::NAN);
        let p0 = state.free.len() as f64;
        let sigma2 = ssr0 / (m - p0).max(1.0);
        let mut eligible: Vec<(usize, f64, usize)> = table
            .iter()
            .filter(|(e, c)| c.status == CandidateStatus::NotSelected && !rejected.contains(e))
            .map(|(e, c)| {
                let gain = c.score - c.parameters as f64 * sigma2 * m.ln();
                (*e, gain, c.parameters)
            })
            .filter(|(_, gain, _)| *gain > 0.0)
            .collect();
        eligible.sort_by(|a, b| b.1.total_cmp(&a.1));
        let k_count = eligible.len().max(1);
        let f_threshold = diag.alpha / k_count as f64;
        let held_before = run.held_out_distances(&state.last.x);
        let mut accepted = false;
        for &(e, _, k) in eligible.iter().take(diag.trials.max(1)) {
            let label = auto.pool[e].label();
            let cols: Vec<usize> = run
                .model
                .effects()
                .get(e)
                .map(|(_, r)| r.clone().collect())
                .unwrap_or_default();
            let mut columns = state.free.clone();
            columns.extend(&cols);
            let (trial_free, trial_fixed) = run.identify(&state.last.x, &columns)?;
            if cols.iter().any(|c| !trial_free.contains(c)) {
                out.trials.push(Trial {
                    label,
                    rms: f64::NAN,
                    val_rms: None,
                    f: 0.0,
                    f_p: 1.0,
                    f_threshold,
                    bic: (f64::NAN, f64::NAN),
                    held_out: None,
                    accepted: false,
                    reason: "not identifiable with the estimated parameters".into(),
                });
                rejected.push(e);
                continue;
            }
            let (outcome, report) = run.step(&format!("+{label}"), &state.last.x, &trial_free)?;
            // Both fits judged with the distances weighted alike.
            let ssr1 = fit::sum_of_squares(&run.problem(sigma0), &outcome.x).unwrap_or(f64::NAN);
            let p1 = trial_free.len() as f64;
            let dof = (m - p1).max(1.0);
            let f = ((ssr0 - ssr1) / k as f64) / (ssr1 / dof).max(1e-300);
            let f_p = stats::f_sf(f, k as f64, dof);
            let bics = (bic(ssr0, m, p0), bic(ssr1, m, p1));
            let held_after = run.held_out_distances(&outcome.x);
            let pairs: Vec<usize> = (0..held_after.len()).collect();
            let held_out = paired_wilcoxon(&held_before, &held_after, &pairs);
            let mut reasons = Vec::new();
            if f_p.is_nan() || f_p >= f_threshold {
                reasons.push(format!("F-to-enter p = {f_p:.2e} >= {f_threshold:.2e}"));
            }
            if bics.1.is_nan() || bics.1 >= bics.0 {
                reasons.push("BIC does not decrease".to_string());
            }
            match held_out {
                Some((_, p)) if p < diag.alpha => {}
                Some((_, p)) => {
                    reasons.push(format!(
                        "held-out improvement p = {p:.2e} >= {}",
                        diag.alpha
                    ));
                }
                None if !held_after.is_empty() => {
                    reasons.push("held-out improvement cannot be tested".to_string());
                }
                None => {}
            }
            let ok = reasons.is_empty();
            out.trials.push(Trial {
                label,
                rms: report.rms,
                val_rms: report.val_rms,
                f,
                f_p,
                f_threshold,
                bic: bics,
                held_out,
                accepted: ok,
                reason: reasons.join("; "),
            });
            if let Some(c) = out
                .candidates
                .iter_mut()
                .find(|c| c.label == auto.pool[e].label() && c.val_rms.is_none())
            {
                c.val_rms = report.val_rms;
            }
            if ok {
                out.selected.push(e);
                let label = report.label.clone();
                state.steps.push(report);
                state
                    .consistency
                    .extend(run.consistency(&label, &outcome.x));
                state.last = outcome;
                state.free = trial_free;
                // What the geometric step could not identify stays fixed.
                state.fixed.extend(trial_fixed);
                accepted = true;
                // A rejection in one round may pass once another effect is in.
                rejected.clear();
                break;
            }
            run.sigma_point = sigma0;
            rejected.push(e);
        }
        if !accepted {
            break;
        }
    }
    for c in &mut out.candidates {
        let e = auto.pool.iter().position(|p| p.label() == c.label);
        c.status = match e {
            Some(e) if out.selected.contains(&e) => CandidateStatus::Selected,
            _ if out.trials.iter().any(|t| t.label == c.label && !t.accepted) => {
                CandidateStatus::Rejected
            }
            _ => c.status,
        };
    }
    Ok(out)
}

/// Parameter estimates of the model's own parameters in the report's layout: pose blocks as
/// `x y z` metres and roll-pitch-yaw radians (their standard errors are those of the block's
/// small-motion parameters, equal to first order for the small corrections fitted here), DH
/// parameters as nominal value plus error, targets in the tip frame.
fn estimates(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    targets_nominal: &[Vector3<f64>],
) -> Vec<ParameterEstimate> {
    let params = model.parameters();
    let nominal = model.nominal();
    let free = |c: usize| fit.free.contains(&c);
    let std = |c: usize| fit.std_errors.get(c).copied().flatten();
    let mut out = Vec::with_capacity(params.len());
    for (c, p) in params.iter().enumerate() {
        let axis = match p.field {
            Field::X | Field::Rx => 0,
            Field::Y | Field::Ry => 1,
            _ => 2,
        };
        let rot = usize::from(matches!(p.field, Field::Rx | Field::Ry | Field::Rz)) * 3;
        let pose = |nom: &Isometry3<f64>| {
            (
                xyz_rpy(nom)[axis + rot],
                xyz_rpy(&model.pose_at(x, p.block))[axis + rot],
            )
        };
        let (nom, est) = match p.block {
            Block::Device | Block::Session(_) => pose(&Isometry3::identity()),
            Block::Base => pose(&nominal.base),
            Block::Tool => pose(&nominal.tool),
            Block::Mount(b) => pose(
                &model
                    .tree()
                    .branches()
                    .get(b)
                    .map_or_else(Isometry3::identity, |br| br.table.base),
            ),
            Block::Joint(r) => {
                let row = &nominal.rows[r];
                let nom = match p.field {
                    Field::A => row.a,
                    Field::Alpha => row.alpha,
                    Field::D => row.d,
                    Field::Theta => row.theta,
                    Field::Beta => row.beta,
                    _ => 0.0,
                };
                (nom, nom + x[c])
            }
            Block::Target(k) => (
                targets_nominal.get(k).map_or(0.0, |t| t[axis]),
                model.target_at(x, k)[axis],
            ),
            Block::Effect(_) => (0.0, x[c]),
        };
        out.push(ParameterEstimate {
            name: p.name.clone(),
            nominal: nom,
            estimate: est,
            std_error: std(c),
            free: free(c),
        });
    }
    out
}

/// The Jacobian of the problem at `x` by central differences (step `h` in parameter units),
/// row-major over all blocks; for tests of the analytic one.
pub fn numeric_jacobian(problem: &SocketProblem<'_>, x: &[f64], h: f64) -> DMatrix<f64> {
    let n = problem.parameter_count();
    let rows: usize = (0..problem.block_count())
        .map(|b| problem.block_size(b))
        .sum();
    let mut j = DMatrix::zeros(rows, n);
    let mut xp = x.to_vec();
    let mut rp = [0.0; 3];
    let mut rm = [0.0; 3];
    for c in 0..n {
        let mut row = 0;
        for b in 0..problem.block_count() {
            let m = problem.block_size(b);
            xp[c] = x[c] + h;
            problem.residuals(&xp, b, &mut rp[..m]);
            xp[c] = x[c] - h;
            problem.residuals(&xp, b, &mut rm[..m]);
            xp[c] = x[c];
            for i in 0..m {
                j[(row + i, c)] = (rp[i] - rm[i]) / (2.0 * h);
            }
            row += m;
        }
    }
    j
}
