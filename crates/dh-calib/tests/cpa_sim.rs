//! Circle-point analysis on simulated sweeps of known DH tables (10 µm noise per coordinate):
//! axes, sense, the geometric fit's freedom from bias, prismatic joints, coupled sweeps, and a
//! planted gear-ratio error.

use std::f64::consts::{FRAC_PI_2, PI};

use approx::assert_relative_eq;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use dh_calib::cpa::{analyse, fit_circle, CircleMethod, CpaError, CpaOptions};
use dh_calib::data::{Measurements, Sample, Split};
use dh_core::{Convention, DhRow, DhTable, JointKind, Line, Tolerance};

/// A robot under a measuring device: a DH table in its base frame, the base in the device frame,
/// targets in the tool frame, and mechanisms the table does not know.
struct Rig {
    table: DhTable,
    device_from_base: Isometry3<f64>,
    targets: Vec<Vector3<f64>>,
    /// Fanuc J2/J3 interaction: the serial angle of `follower` is `q_follower + q_lead`.
    interaction: Option<(usize, usize)>,
    /// The joint turns `ratio` times the commanded value.
    gear: Option<(usize, f64)>,
}

impl Rig {
    /// Serial joint values the table sees for commanded `q`.
    fn serial(&self, q: &[f64]) -> Vec<f64> {
        let mut s = q.to_vec();
        if let Some((lead, follower)) = self.interaction {
            s[follower] += q[lead];
        }
        if let Some((j, ratio)) = self.gear {
            s[j] *= ratio;
        }
        s
    }

    /// Target `t` in the device frame at commanded `q`.
    fn point(&self, q: &[f64], t: usize) -> Vector3<f64> {
        let fk = self.table.fk(&self.serial(q)).unwrap();
        (self.device_from_base * fk * nalgebra::Point3::from(self.targets[t])).coords
    }

    /// The true joint axes at q = 0 in the device frame (standard DH: joint i on z of frame
    /// i − 1).
    fn axes(&self) -> Vec<Line> {
        let zeros = vec![0.0; self.table.rows.len()];
        let frames = self.table.frames(&zeros).unwrap();
        frames[..self.table.rows.len()]
            .iter()
            .map(|f| {
                let f = self.device_from_base * f;
                Line::through(f.translation.vector, f.rotation * Vector3::z()).unwrap()
            })
            .collect()
    }

    /// Measures every target at each configuration of `plan` (one sweep after another), with
    /// Gaussian noise of `sigma` per coordinate.
    fn measure(&self, plan: &[Vec<f64>], sigma: f64, seed: u64) -> Measurements {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        let mut samples = Vec::new();
        for (i, q) in plan.iter().enumerate() {
            for t in 0..self.targets.len() {
                let e = Vector3::from_fn(|_, _| noise.sample(&mut rng));
                samples.push(Sample {
                    time: None,
                    orientation: None,
                    session: 0,
                    q: q.as_slice().into(),
                    target: t,
                    point: self.point(q, t) + e,
                    sigma: None,
                    config: Some(i.to_string().into()),
                    split: Split::Calibration,
                    line: 0,
                    socket: None,
                });
            }
        }
        Measurements {
            sessions: Vec::new(),
            joint_names: self.table.rows.iter().map(|r| r.name.clone()).collect(),
            targets: (0..self.targets.len()).map(|t| format!("T{t}")).collect(),
            samples,
        }
    }
}

/// A Fanuc R-2000iC-like 6R arm (standard DH, metres), 3 m in front of a tracker, three
/// reflectors on a tool plate.
fn fanuc_like() -> Rig {
    let rows = vec![
        DhRow::revolute("j1", 0.312, -FRAC_PI_2, 0.670, 0.0),
        DhRow::revolute("j2", 1.075, 0.0, 0.0, -FRAC_PI_2),
        DhRow::revolute("j3", 0.225, -FRAC_PI_2, 0.0, 0.0),
        DhRow::revolute("j4", 0.0, FRAC_PI_2, 1.280, 0.0),
        DhRow::revolute("j5", 0.0, -FRAC_PI_2, 0.0, 0.0),
        DhRow::revolute("j6", 0.0, 0.0, 0.215, 0.0),
    ];
    Rig {
        table: DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows,
        },
        device_from_base: Isometry3::from_parts(
            Translation3::new(-1.4, -3.7, -0.7),
            UnitQuaternion::from_euler_angles(0.004, -0.006, 0.38),
        ),
        targets: vec![
            Vector3::new(0.20, 0.0, 0.05),
            Vector3::new(-0.10, 0.18, 0.08),
            Vector3::new(-0.12, -0.16, 0.12),
        ],
        interaction: None,
        gear: None,
    }
}

/// One sweep per joint: joint `j` takes `values` (radians) with the others at `home`.
fn plan(home: &[f64], values: &[f64]) -> Vec<Vec<f64>> {
    let mut out = Vec::new();
    for j in 0..home.len() {
        for &v in values {
            let mut q = home.to_vec();
            q[j] = home[j] + v;
            out.push(q);
        }
    }
    out
}

fn degrees(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step).round() as usize;
    (0..=n)
        .map(|i| (from + step * i as f64).to_radians())
        .collect()
}

/// Largest direction error (rad) and position error (m, at the point of the true axis nearest
/// the targets' centroid at q = 0) over the axes.
fn axis_errors(rig: &Rig, found: &[Line]) -> (f64, f64) {
    let zeros = vec![0.0; rig.table.rows.len()];
    let centroid = (0..rig.targets.len())
        .map(|t| rig.point(&zeros, t))
        .sum::<Vector3<f64>>()
        / rig.targets.len() as f64;
    let mut worst = (0.0f64, 0.0f64);
    for (truth, line) in rig.axes().iter().zip(found) {
        let angle = truth.angle_to(line);
        let near = truth.foot_of(&centroid);
        worst = (
            worst.0.max(angle),
            worst.1.max(line.distance_to_point(&near)),
        );
    }
    worst
}

const HOME: [f64; 6] = [0.3, -0.2, 0.25, 0.4, -0.5, 0.1];

#[test]
fn full_circles_recover_every_axis_and_its_sense() {
    let rig = fanuc_like();
    // Not starting at 0: a sweep ending where the next one starts would absorb the return.
    let m = rig.measure(&plan(&HOME, &degrees(10.0, 325.0, 45.0)), 10e-6, 1);
    let r = analyse(&m, &CpaOptions::default()).unwrap();
    assert_eq!(r.sweeps.len(), 6);
    let lines: Vec<Line> = r.axes.iter().map(|a| a.line).collect();
    let (angle, position) = axis_errors(&rig, &lines);
    assert!(angle < 1e-4, "direction error {angle} rad");
    assert!(position < 50e-6, "position error {position} m");
    for j in &r.joints {
        // Radial noise is σ = 10 µm less what the fit absorbs.
        assert!(
            j.circle_rms < 20e-6 && j.circle_rms > 3e-6,
            "{}: {}",
            j.name,
            j.circle_rms
        );
        assert!(j.motion.rms < 1e-4, "{}: {}", j.name, j.motion.rms);
        assert_eq!(j.points, 24);
    }
}

#[test]
fn sixty_degree_arcs_recover_every_axis() {
    // On a 60° arc the centre along the arc's bisector is weakly determined (only the arc's
    // curvature fixes it), so single runs scatter: judge the RMS error over
    // ten noise draws. 13 poses per sweep, 3 targets, 10 µm.
    let rig = fanuc_like();
    let runs = 10;
    let mut sq = [(0.0f64, 0.0f64); 6];
    let zeros = [0.0; 6];
    let centroid = (0..3).map(|t| rig.point(&zeros, t)).sum::<Vector3<f64>>() / 3.0;
    for seed in 0..runs {
        let m = rig.measure(&plan(&HOME, &degrees(-30.0, 30.0, 5.0)), 10e-6, 100 + seed);
        let r = analyse(&m, &CpaOptions::default()).unwrap();
        for (j, (truth, found)) in rig.axes().iter().zip(&r.axes).enumerate() {
            sq[j].0 += truth.angle_to(&found.line).powi(2);
            sq[j].1 += found
                .line
                .distance_to_point(&truth.foot_of(&centroid))
                .powi(2);
        }
        for j in &r.joints {
            assert_relative_eq!(j.span, 60f64.to_radians(), epsilon = 1e-12);
            assert_eq!(j.poses, 13);
            // Pure noise: no gear-ratio error beyond what 10 µm allows.
            let slope = j.motion.linear.unwrap().slope;
            assert!(slope.abs() < 3e-4, "{}: slope {slope}", j.name);
            assert!(j.motion.combined.is_none());
        }
    }
    for (j, (a, p)) in sq.iter().enumerate() {
        let (angle, position) = ((a / runs as f64).sqrt(), (p / runs as f64).sqrt());
        assert!(angle < 1e-4, "j{}: RMS direction error {angle} rad", j + 1);
        assert!(
            position < 50e-6,
            "j{}: RMS position error {position} m",
            j + 1
        );
    }
}

#[test]
fn extracted_table_reproduces_the_measured_points() {
    let rig = fanuc_like();
    let m = rig.measure(&plan(&HOME, &degrees(-30.0, 30.0, 5.0)), 10e-6, 3);
    let opts = CpaOptions {
        // The measured j2 ∥ j3 are a few µrad off parallel: snap them.
        tolerance: Tolerance::new(1e-5, 1e-3).unwrap(),
        ..CpaOptions::default()
    };
    let r = analyse(&m, &opts).unwrap();
    let table = &r.extraction.table;
    // The targets in the tip frame the analysis defined, from their true positions at q = 0.
    let zeros = [0.0; 6];
    let in_tip: Vec<Vector3<f64>> = (0..3)
        .map(|t| (r.tip.inverse() * nalgebra::Point3::from(rig.point(&zeros, t))).coords)
        .collect();
    let mut worst = 0.0f64;
    for q in [
        [0.1, 0.2, -0.3, 0.5, 0.7, -1.0],
        [-0.4, 0.1, 0.3, -1.2, 0.4, 2.0],
    ] {
        let fk = table.fk(&q).unwrap();
        for (t, p) in in_tip.iter().enumerate() {
            let err = (fk * nalgebra::Point3::from(*p)).coords - rig.point(&q, t);
            worst = worst.max(err.norm());
        }
    }
    assert!(worst < 150e-6, "FK error {worst} m");
    // The DH lengths of the nominal arm come back (to the noise and the snap).
    let rows = &table.rows;
    assert_relative_eq!(rows[0].a.abs(), 0.312, epsilon = 3e-4);
    assert_relative_eq!(rows[1].a.abs(), 1.075, epsilon = 3e-4);
    assert_relative_eq!(rows[2].a.abs(), 0.225, epsilon = 3e-4);
    assert_relative_eq!(rows[3].d.abs(), 1.280, epsilon = 3e-4);
}

#[test]
fn geometric_fit_is_unbiased_on_a_sixty_degree_arc_and_kasa_is_not() {
    // 2000 arcs of radius 0.1 m, 60 degrees, 25 points, noise 0.5 mm per coordinate.
    let (radius, sigma, trials) = (0.1, 0.5e-3, 2000);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let noise = Normal::new(0.0, sigma).unwrap();
    let (mut kasa, mut geometric) = (Vec::new(), Vec::new());
    for _ in 0..trials {
        let pts: Vec<Vector3<f64>> = degrees(0.0, 60.0, 2.5)
            .iter()
            .map(|a| {
                let p = Vector3::new(radius * a.cos(), radius * a.sin(), 0.0);
                p + Vector3::from_fn(|_, _| noise.sample(&mut rng))
            })
            .collect();
        kasa.push(fit_circle(&pts, CircleMethod::Kasa).unwrap().radius - radius);
        geometric.push(fit_circle(&pts, CircleMethod::Geometric).unwrap().radius - radius);
    }
    let stats = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        (mean, (var / v.len() as f64).sqrt())
    };
    let (k_mean, k_se) = stats(&kasa);
    let (g_mean, g_se) = stats(&geometric);
    // Kåsa shrinks the circle by many standard errors; the geometric fit is within three.
    assert!(k_mean < -5.0 * k_se, "Kasa bias {k_mean} ± {k_se}");
    assert!(
        g_mean.abs() < 3.0 * g_se,
        "geometric bias {g_mean} ± {g_se}"
    );
    assert!(k_mean.abs() > 4.0 * g_mean.abs());
}

/// A SCARA: two revolute joints, a prismatic quill along −z, a revolute tool.
fn scara() -> Rig {
    let rows = vec![
        DhRow::revolute("r1", 0.35, 0.0, 0.4, 0.0),
        DhRow::revolute("r2", 0.30, PI, 0.0, 0.0),
        DhRow::prismatic("p3", 0.0, 0.0, 0.1, 0.0),
        DhRow::revolute("r4", 0.0, 0.0, 0.05, 0.0),
    ];
    Rig {
        table: DhTable {
            convention: Convention::Standard,
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            rows,
        },
        device_from_base: Isometry3::from_parts(
            Translation3::new(1.2, 0.4, -0.3),
            UnitQuaternion::from_euler_angles(0.0, 0.0, -0.7),
        ),
        targets: vec![Vector3::new(0.2, 0.0, 0.02), Vector3::new(-0.1, 0.18, 0.05)],
        interaction: None,
        gear: None,
    }
}

#[test]
fn prismatic_joint_traces_a_line_with_its_direction_recovered() {
    let rig = scara();
    let home = [0.2, -0.4, 0.05, 0.3];
    let mut configs = Vec::new();
    for j in 0..4 {
        for k in 0..11 {
            let mut q = home.to_vec();
            q[j] += match j {
                // The quill travels 0.25 m, the tool rolls a full turn, the arm joints 100°.
                2 => 0.025 * k as f64,
                3 => (15.0 + 33.0 * k as f64).to_radians(),
                _ => (-40.0 + 10.0 * k as f64).to_radians(),
            };
            configs.push(q);
        }
    }
    let m = rig.measure(&configs, 10e-6, 4);
    let opts = CpaOptions {
        prismatic: vec!["p3".into()],
        ..CpaOptions::default()
    };
    let r = analyse(&m, &opts).unwrap();
    let p3 = &r.joints[2];
    assert_eq!(p3.kind, JointKind::Prismatic);
    assert!(p3.radius.is_none() && p3.plane_rms.is_none());
    assert!(p3.circle_rms < 20e-6, "line RMS {}", p3.circle_rms);
    assert!(
        p3.motion.rms < 20e-6,
        "displacement residual {}",
        p3.motion.rms
    );
    let truth = rig.axes();
    let tilt = truth[2].angle_to(&r.axes[2].line);
    assert!(tilt < 1e-4, "prismatic direction error {tilt} rad");
    // The revolute axes keep their positions too (the prismatic one has none).
    for j in [0, 1, 3] {
        let (a, b) = (&truth[j], &r.axes[j].line);
        assert!(a.angle_to(b) < 1e-4, "j{j}: {}", a.angle_to(b));
        let near = a.foot_of(&rig.point(&[0.0; 4], 0));
        assert!(
            b.distance_to_point(&near) < 50e-6,
            "j{j}: {}",
            b.distance_to_point(&near)
        );
    }
    assert_eq!(r.extraction.table.rows[2].kind, JointKind::Prismatic);
}

#[test]
fn planted_gear_ratio_error_shows_as_slope() {
    let mut rig = fanuc_like();
    rig.gear = Some((1, 1.001));
    let m = rig.measure(&plan(&[0.0; 6], &degrees(-60.0, 60.0, 10.0)), 10e-6, 5);
    let r = analyse(&m, &CpaOptions::default()).unwrap();
    for j in &r.joints {
        let slope = j.motion.linear.unwrap().slope;
        if j.joint == 1 {
            assert_relative_eq!(slope, 1e-3, epsilon = 2e-5);
            // 1000 ppm over ±60° is 3.6 arcsec per degree: far above the noise.
            assert!(j.motion.rms > 10.0 * j.motion.linear.unwrap().rms);
        } else {
            // Noise alone: 10 µm on radii of 0.2 m and more.
            assert!(slope.abs() < 1e-4, "{}: {slope}", j.name);
        }
    }
}

#[test]
fn once_per_turn_error_shows_as_sinusoid_on_a_full_turn() {
    // Joint 4 runs ahead of its reported value by 500 µrad (100 arcsec) · sin(q + 0.5), as
    // behind an eccentric output gear.
    let rig = fanuc_like();
    let configs = plan(&HOME, &degrees(15.0, 345.0, 30.0));
    let mut m = rig.measure(&configs, 10e-6, 6);
    for (i, q) in configs.iter().enumerate() {
        if i / 12 == 3 {
            let true_q = q[3];
            let reported = true_q - 5e-4 * (true_q + 0.5).sin();
            for s in &mut m.samples[3 * i..3 * i + 3] {
                let mut q = s.q.to_vec();
                q[3] = reported;
                s.q = q.into();
            }
        }
    }
    let r = analyse(&m, &CpaOptions::default()).unwrap();
    let j4 = &r.joints[3];
    let combined = j4.motion.combined.unwrap();
    assert_relative_eq!(combined.amplitude, 5e-4, epsilon = 5e-5);
    assert_relative_eq!(combined.phase, 0.5, epsilon = 0.1);
    assert!(combined.slope.abs() < 2e-5);
    let sinusoid = j4.motion.sinusoid.unwrap();
    assert_relative_eq!(sinusoid.amplitude, 5e-4, epsilon = 5e-5);
    assert!(combined.rms < 0.2 * j4.motion.rms);
}

#[test]
fn fanuc_interaction_sweep_of_j2_with_j3_counter_rotated_is_j2s_axis() {
    let mut rig = fanuc_like();
    rig.interaction = Some((1, 2));
    // Boby's plan: J2 swept with J3 = −J2, all other sweeps one joint at a time.
    let mut configs = Vec::new();
    for j in 0..6 {
        for v in degrees(-45.0, 45.0, 5.0) {
            let mut q = HOME.to_vec();
            q[j] += v;
            if j == 1 {
                q[2] -= v;
            }
            configs.push(q);
        }
    }
    let m = rig.measure(&configs, 10e-6, 8);
    let r = analyse(&m, &CpaOptions::default()).unwrap();
    let j2 = &r.sweeps[r.joints[1].sweep];
    assert_eq!(j2.coupled.len(), 1);
    assert_eq!(j2.coupled[0].name, "j3");
    assert_relative_eq!(j2.coupled[0].ratio, -1.0, epsilon = 1e-12);
    // Axes at q = 0 in serial variables (θ3 = q3 + q2) are the table's.
    let lines: Vec<Line> = r.axes.iter().map(|a| a.line).collect();
    let (angle, position) = axis_errors(&rig, &lines);
    assert!(angle < 1e-4, "direction error {angle} rad");
    assert!(position < 50e-6, "position error {position} m");
    // The targets' J2 circles are concentric.
    for t in &r.joints[1].targets {
        assert!(t.axis_offset < 50e-6, "{}: {}", t.name, t.axis_offset);
    }
}

#[test]
fn counter_rotation_on_a_plain_serial_arm_is_not_a_rotation_about_j2() {
    let rig = fanuc_like();
    let mut configs = Vec::new();
    for j in 0..6 {
        for v in degrees(-30.0, 30.0, 10.0) {
            let mut q = HOME.to_vec();
            q[j] += v;
            if j == 1 {
                q[2] -= v;
            }
            configs.push(q);
        }
    }
    let m = rig.measure(&configs, 10e-6, 9);
    let e = analyse(&m, &CpaOptions::default()).unwrap_err();
    // Circles a forearm apart: millimetres about a common axis against micrometres about their
    // own.
    let CpaError::NotRigid { common, own, .. } = e.clone() else {
        panic!("expected NotRigid, found {e}");
    };
    assert!(common > 1e-3 && own < 20e-6, "{common} {own}");
    let text = e.to_string();
    assert!(
        text.starts_with("j2 swept together with j3: the targets' circles are not concentric"),
        "{text}"
    );
}

#[test]
fn missing_sweeps_are_named() {
    let rig = fanuc_like();
    let all = plan(&HOME, &degrees(10.0, 60.0, 10.0));
    // Only joints 1-4 swept.
    let m = rig.measure(&all[..24], 10e-6, 10);
    let e = analyse(&m, &CpaOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no sweep of 'j5', 'j6' found; sweeps found: j1: 6 poses, 50.0 deg; j2: 6 poses, 50.0 deg; \
         j3: 6 poses, 50.0 deg; j4: 6 poses, 50.0 deg"
    );
}
