//! Outliers that are an effect's evidence (issue 33 §4, the cases the judgement against the
//! final model could not mend): the geometric screen leaves out the very poses that show a
//! direction backlash, so the selection, judging candidates without them, never finds it.
//!
//! Planted on a UR5 with 20 µm of tracker noise per axis, 100 poses sweeping the shoulder
//! lift (`j2`) upward and reversing it every few poses; random geometric errors of 0.5 mm and
//! 1 mrad:
//! - (a) a 70 µrad backlash reversed at every fourth pose, the two reversed poses it moves most
//!   and every fifth other pose held out for validation, a 3 mm lost beam among the
//!   calibration points and a 2 mm one among the validation points. The geometric screen
//!   leaves out one reversed held-out pose (besides the lost beams); without it the backlash's
//!   held-out test failed (seed 65: F p = 1.6e-48, held-out p = 0.0155; seed 71: 2.0e-28 and
//!   0.0134 against 0.01). The held-out test now counts a left-out validation point that the
//!   candidate's fit (or the fit before it) explains, for both fits.
//! - (b) a 100 µrad backlash reversed at every eighth pose, no validation split: the geometric
//!   screen leaves out 6 to 8 of the 12 reversed poses, all clean, and the backlash's direction
//!   column is then inert (the joint hardly reverses in the points kept); the diagnosis said
//!   "model complete", nothing selected, naming them as outliers. The left-out points are now
//!   judged against each candidate, and those the backlash explains are given back.

mod fit_support;

use dh_calib::calibrate::{screen, CalibrationOptions, Report};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose, DiagnoseOptions};
use dh_calib::effects::parse_label;
use dh_calib::model::ModelOptions;
use dh_calib::simulate::{plant_effects, simulate, Errors, SimulationOptions};
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use nalgebra::Vector3;

/// Tracker noise per axis (metres).
const SIGMA: f64 = 2e-5;

/// How one set is made.
struct Plan {
    seed: u64,
    /// The planted direction backlash of `j2` (radians).
    backlash: f64,
    /// Every this many poses of the upward sweep, the joint's direction is reversed once.
    reverse_every: usize,
    /// Held out: this many reversed poses (those the backlash moves most) and every fifth
    /// other pose (none when 0).
    reversed_held: usize,
    /// A 3 mm lost beam on this calibration pose (approached upward).
    lost_cal: Option<usize>,
    /// A 2 mm lost beam on the first held-out pose approached upward after the sixth.
    lost_val: bool,
}

/// The set (lines numbered from 2), whether each sample's pose was reached moving `j2`
/// downward, and the lines of the lost beams.
fn data(p: &Plan) -> (Measurements, Vec<bool>, Vec<usize>) {
    let table = fit_support::ur5();
    let (mut m, truth) = simulate(
        &table,
        &SimulationOptions {
            seed: p.seed,
            poses: 100,
            sigma: SIGMA,
            errors: Errors::Random {
                length: 5e-4,
                angle: 1e-3,
            },
            device: Some(from_xyz_rpy([1.5, -0.5, 0.4], [0.0, 0.0, 2.5])),
            validation_fraction: 0.0,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    m.samples.sort_by(|a, b| a.q[1].total_cmp(&b.q[1]));
    let mut reversed = vec![false; m.samples.len()];
    let mut k = p.reverse_every / 2;
    while k + 1 < m.samples.len() {
        m.samples.swap(k, k + 1);
        reversed[k + 1] = true;
        k += p.reverse_every;
    }
    for (i, s) in m.samples.iter_mut().enumerate() {
        s.line = i + 2;
        s.config = Some(format!("p{i}").into());
    }
    let clean = m.clone();
    plant_effects(
        &table,
        &mut m,
        &truth,
        &[(
            parse_label("backlash_direction:j2", &table).unwrap_or_else(|e| panic!("{e}")),
            vec![p.backlash],
        )],
        &ModelOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut moved: Vec<(f64, usize)> = (0..m.samples.len())
        .filter(|&i| reversed[i])
        .map(|i| ((m.samples[i].point - clean.samples[i].point).norm(), i))
        .collect();
    moved.sort_by(|a, b| b.0.total_cmp(&a.0));
    for &(_, i) in moved.iter().take(p.reversed_held) {
        m.samples[i].split = Split::Validation;
    }
    if p.reversed_held > 0 {
        for (i, s) in m.samples.iter_mut().enumerate() {
            if !reversed[i] && i % 5 == 3 {
                s.split = Split::Validation;
            }
        }
    }
    let mut lost = Vec::new();
    if let Some(l) = p.lost_cal {
        assert!(!reversed[l] && m.samples[l].split == Split::Calibration);
        m.samples[l].point += Vector3::new(3e-3, -1e-3, 0.0);
        lost.push(m.samples[l].line);
    }
    if p.lost_val {
        let l = (0..m.samples.len())
            .find(|&i| !reversed[i] && i > 5 && m.samples[i].split == Split::Validation)
            .unwrap_or_else(|| panic!("no held-out pose"));
        m.samples[l].point += Vector3::new(0.0, 1.5e-3, -1.3e-3);
        lost.push(m.samples[l].line);
    }
    (m, reversed, lost)
}

fn named(r: &Report) -> Vec<usize> {
    let mut v: Vec<usize> = r
        .outliers
        .as_ref()
        .map(|o| o.outliers.iter().map(|p| p.line).collect())
        .unwrap_or_default();
    v.sort_unstable();
    v
}

/// The selected backlash: its estimate covers the truth.
fn backlash_found(r: &Report, truth: f64) {
    assert_eq!(
        r.selected_effects,
        vec!["backlash_direction:j2".to_string()],
        "{:?}",
        r.notes
    );
    let p = r
        .parameters
        .iter()
        .find(|p| p.name == "backlash_direction:j2")
        .unwrap_or_else(|| panic!("{:?}", r.parameters));
    let se = p.std_error.unwrap_or(f64::INFINITY);
    assert!(
        (p.estimate - truth).abs() < 3.0 * se,
        "{} ± {se}",
        p.estimate
    );
    assert_eq!(r.verdict.summary, "model complete");
}

fn plan_a(seed: u64) -> Plan {
    Plan {
        seed,
        backlash: 7e-5,
        reverse_every: 4,
        reversed_held: 2,
        lost_cal: Some(20),
        lost_val: true,
    }
}

fn plan_b(seed: u64) -> Plan {
    Plan {
        seed,
        backlash: 1e-4,
        reverse_every: 8,
        reversed_held: 0,
        lost_cal: None,
        lost_val: false,
    }
}

#[test]
fn a_left_out_reversed_validation_pose_counts_in_the_backlash_held_out_test() {
    for seed in [65, 71] {
        let plan = plan_a(seed);
        let (m, reversed, mut lost) = data(&plan);
        lost.sort_unstable();
        // The premise: the geometric screen leaves out one clean reversed held-out pose.
        let tree = DhTree::serial(&fit_support::ur5());
        let s = screen(&tree, &m, &CalibrationOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let clean: Vec<_> = s
            .outliers
            .iter()
            .filter(|o| !lost.contains(&o.line))
            .collect();
        assert_eq!(clean.len(), 1, "seed {seed}: {:?}", s.outliers);
        assert!(clean[0].validation && reversed[clean[0].line - 2]);
        let r = diagnose(
            &fit_support::ur5(),
            &m,
            &CalibrationOptions::default(),
            &DiagnoseOptions::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let trial = r
            .diagnosis
            .as_ref()
            .and_then(|d| d.rounds.first())
            .and_then(|round| round.trials.first())
            .unwrap_or_else(|| panic!("seed {seed}: no trial"));
        assert_eq!(trial.label, "backlash_direction:j2");
        let (_, p) = trial.held_out.unwrap_or_else(|| panic!("no held-out test"));
        assert!(trial.accepted && p < 0.01, "seed {seed}: {trial:?}");
        backlash_found(&r, plan.backlash);
        // Only the lost beams stay out; the reversed pose is given back.
        assert_eq!(named(&r), lost, "seed {seed}: {:?}", r.outliers);
        let o = r.outliers.as_ref().unwrap_or_else(|| panic!("no screen"));
        assert!(
            o.given_back
                .iter()
                .any(|g| g.line == clean[0].line && g.validation),
            "seed {seed}: {:?}",
            o.given_back
        );
    }
}

#[test]
fn every_reversed_pose_left_out_is_given_back_with_the_backlash() {
    for seed in [13, 20] {
        let plan = plan_b(seed);
        let (m, reversed, _) = data(&plan);
        // The premise: the geometric screen leaves out most reversed poses and nothing else.
        let tree = DhTree::serial(&fit_support::ur5());
        let s = screen(&tree, &m, &CalibrationOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let out: Vec<usize> = s.outliers.iter().map(|o| o.line).collect();
        assert!(out.len() >= 6, "seed {seed}: {out:?}");
        assert!(out.iter().all(|&l| reversed[l - 2]), "seed {seed}: {out:?}");
        let r = diagnose(
            &fit_support::ur5(),
            &m,
            &CalibrationOptions::default(),
            &DiagnoseOptions::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        backlash_found(&r, plan.backlash);
        assert_eq!(named(&r), Vec::<usize>::new(), "seed {seed}");
        let o = r.outliers.as_ref().unwrap_or_else(|| panic!("no screen"));
        let mut back: Vec<usize> = o.given_back.iter().map(|g| g.line).collect();
        back.sort_unstable();
        assert_eq!(back, out, "seed {seed}");
        assert!(o
            .given_back
            .iter()
            .all(|g| g.after.sigmas < g.after.threshold));
    }
}

#[test]
fn a_lost_beam_among_the_reversed_poses_stays_out() {
    // (b) with a 3 mm lost beam: the backlash explains the reversed poses, not the beam.
    let plan = Plan {
        lost_cal: Some(30),
        ..plan_b(19)
    };
    let (m, _, lost) = data(&plan);
    let r = diagnose(
        &fit_support::ur5(),
        &m,
        &CalibrationOptions::default(),
        &DiagnoseOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    backlash_found(&r, plan.backlash);
    assert_eq!(named(&r), lost);
}
