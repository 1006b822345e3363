//! Unit tests of circle-point analysis.

use super::*;
use approx::assert_relative_eq;

fn set(qs: &[[f64; 2]]) -> Measurements {
    Measurements {
        sessions: Vec::new(),
        joint_names: vec!["a".into(), "b".into()],
        targets: vec!["t".into()],
        samples: qs
            .iter()
            .enumerate()
            .map(|(i, q)| crate::data::Sample {
                time: None,
                orientation: None,
                session: 0,
                q: q.as_slice().into(),
                target: 0,
                point: Vector3::zeros(),
                sigma: None,
                config: None,
                split: crate::data::Split::Calibration,
                line: i + 1,
                socket: None,
            })
            .collect(),
    }
}

/// Lead joint, (follower, ratio), poses, first and last line.
type Summary = (usize, Vec<(usize, f64)>, usize, (usize, usize));

#[test]
fn sweeps_by_hand_repeats_transitions_coupling_and_shared_ends() {
    let m = set(&[
        // a alone, the first pose measured twice.
        [0.0, 0.0],
        [0.0, 0.0],
        [1.0, 0.0],
        [2.0, 0.0],
        [3.0, 0.0],
        // Transition: both change, in another proportion than what follows.
        [2.5, 1.0],
        // a with b = -a.
        [3.5, 0.0],
        [4.5, -1.0],
        [5.5, -2.0],
        // b alone, starting where the coupled sweep ends.
        [5.5, -1.0],
        [5.5, 0.0],
        [5.5, 1.0],
    ]);
    let opts = CpaOptions::default();
    let poses = group_poses(&m, opts.unchanged);
    assert_eq!(poses.len(), 11);
    let sweeps = find_sweeps(&m, &poses, &opts);
    let summary: Vec<Summary> = sweeps
        .iter()
        .map(|s| {
            let c = s.coupled.iter().map(|c| (c.joint, c.ratio)).collect();
            (s.joint, c, s.poses, s.lines)
        })
        .collect();
    assert_eq!(
        summary,
        vec![
            (0, vec![], 4, (1, 5)),
            (0, vec![(1, -1.0)], 4, (6, 9)),
            (1, vec![], 4, (9, 12)),
        ]
    );
    assert_eq!(sweeps[0].samples, vec![0, 1, 2, 3, 4]);
    assert_relative_eq!(sweeps[0].span, 3.0);
    assert_eq!(sweeps[2].start, vec![5.5, -2.0]);
}

#[test]
fn bad_input_is_named() {
    let mut m = set(&[[0.0, 0.0], [1.0, 0.0]]);
    m.samples[1].point.y = f64::NAN;
    let e = analyse(&m, &CpaOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 2: expected finite joint values and coordinates, found NaN"
    );
    m.samples[1].q = m.samples[1].q[..1].into();
    let e = analyse(&m, &CpaOptions::default()).unwrap_err();
    assert_eq!(e.to_string(), "line 2: expected 2 joint values, found 1");
    let opts = CpaOptions {
        min_poses: 2,
        ..CpaOptions::default()
    };
    let e = analyse(&set(&[[0.0, 0.0]]), &opts).unwrap_err();
    assert_eq!(
        e.to_string(),
        "option min_poses: expected at least 3, found 2"
    );
    let e = analyse(&set(&[[0.0, 0.0], [1.0, 0.0]]), &CpaOptions::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no sweep of 'a', 'b' found; sweeps found: none"
    );
}

#[test]
fn values_within_the_unchanged_tolerance_are_one_pose() {
    let m = set(&[
        [0.0, 0.0],
        [1e-6, -1e-6],
        [1.0, 0.0],
        [2.0, 3e-6],
        [3.0, 0.0],
    ]);
    let opts = CpaOptions::default();
    let poses = group_poses(&m, opts.unchanged);
    assert_eq!(poses.len(), 4);
    let sweeps = find_sweeps(&m, &poses, &opts);
    assert_eq!(sweeps.len(), 1);
    assert!(sweeps[0].coupled.is_empty());
}

#[test]
fn wrap_stays_in_half_open_interval() {
    assert_relative_eq!(wrap(3.0 * PI), PI, epsilon = 1e-15);
    assert_relative_eq!(wrap(-PI), PI, epsilon = 1e-15);
    assert_relative_eq!(wrap(0.1 - TAU), 0.1, epsilon = 1e-15);
}

#[test]
fn exact_circle_by_hand() {
    // Circle of radius 2 about (1, 2, 3) in the plane x + z = const, normal (1, 0, 1)/√2.
    let n = Vector3::new(1.0, 0.0, 1.0).normalize();
    let u = Vector3::y();
    let v = n.cross(&u);
    let c = Vector3::new(1.0, 2.0, 3.0);
    let pts: Vec<Vector3<f64>> = (0..5)
        .map(|i| {
            let a = 0.3 * f64::from(i);
            c + (u * a.cos() + v * a.sin()) * 2.0
        })
        .collect();
    for method in [CircleMethod::Kasa, CircleMethod::Geometric] {
        let fit = fit_circle(&pts, method).unwrap();
        assert_relative_eq!(fit.centre, c, epsilon = 1e-12);
        assert_relative_eq!(fit.radius, 2.0, epsilon = 1e-12);
        assert_relative_eq!(fit.normal.dot(&n).abs(), 1.0, epsilon = 1e-12);
        assert!(fit.circle_rms < 1e-12 && fit.plane_rms < 1e-12);
    }
}

#[test]
fn collinear_points_are_an_error_not_nan() {
    let pts: Vec<Vector3<f64>> = (0..4).map(|i| Vector3::x() * f64::from(i)).collect();
    let e = fit_circle(&pts, CircleMethod::Geometric).unwrap_err();
    assert!(e.to_string().contains("lie on a line"), "{e}");
    assert!(fit_circle(&pts[..2], CircleMethod::Kasa).is_err());
}

#[test]
fn least_squares_recovers_a_line_and_refuses_rank_deficiency() {
    let q = [0.0, 1.0, 2.0, 3.0];
    let e: Vec<f64> = q.iter().map(|x| 0.5 + 2.0 * x).collect();
    let (c, r) = least_squares(&q, &e, &[Basis::One, Basis::Q]).unwrap();
    assert_relative_eq!(c[1], 2.0, epsilon = 1e-12);
    assert!(r < 1e-12);
    // Every q a multiple of 2π: cos is the constant.
    let q = [0.0, TAU, 2.0 * TAU, 3.0 * TAU];
    assert!(least_squares(&q, &e, &[Basis::One, Basis::Cos, Basis::Sin]).is_none());
}
