//! The closed-form start (module docs, step 1): rigid registration of the nominal model's points
//! to the measured ones (Kabsch 1976; Horn, JOSA A 4(4), 1987) alternated with the closed-form
//! target positions given the device frame.

use super::*;

pub(super) fn observed_position(o: &Observed) -> Vector3<f64> {
    o.observation.position()
}

/// Closed-form target positions given the device frame: the mean of each target's measured
/// points mapped into the tip frame (the exact least-squares solution, rotations being
/// orthogonal).
pub(super) fn targets_given_device(model: &mut Model, x: &[f64], cal: &[Observed]) {
    let k = model.targets().len();
    let mut sums = vec![(Vector3::zeros(), 0usize); k];
    // Each point in its tip frame on every core, summed in order (the same sums).
    let in_tip = fit::in_segments(cal, |o| match &o.observation {
        Observation::Point { target, point } => {
            let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
            Some((
                *target,
                tip.inverse_transform_point(&(*point).into()).coords,
            ))
        }
        _ => None,
    });
    for (target, p) in in_tip.into_iter().flatten() {
        if let Some(s) = sums.get_mut(target) {
            s.0 += p;
            s.1 += 1;
        }
    }
    for (t, (sum, n)) in sums.into_iter().enumerate() {
        if n > 0 {
            model.set_target(t, sum / n as f64);
        }
    }
}

pub(super) fn initialise(
    model: &mut Model,
    x: &[f64],
    cal: &[Observed],
    options: &CalibrationOptions,
) -> Result<(), CalibError> {
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
    let sessions = crate::sessions::sessions_of(cal);
    if let Some(d) = &options.device_guess {
        model.set_device(d);
        if options.target_guesses.is_none() {
            let first: Vec<Observed> = cal
                .iter()
                .filter(|o| Some(&o.session) == sessions.first())
                .cloned()
                .collect();
            targets_given_device(model, x, &first);
        }
        // The other sessions' frames from the targets the guess gives.
        for (s, t) in
            crate::sessions::register_each(model, x, cal, sessions.get(1..).unwrap_or(&[]))?
        {
            model.set_session_device(s, &t);
        }
        return Ok(());
    }
    // Alternate registration (each session's frame) and targets; a few rounds reach the basin
    // of the least squares.
    let rounds = if options.target_guesses.is_some() {
        1
    } else {
        4
    };
    for _ in 0..rounds {
        for (s, t) in crate::sessions::register_each(model, x, cal, &sessions)? {
            model.set_session_device(s, &t);
        }
        if options.target_guesses.is_none() {
            targets_given_device(model, x, cal);
        }
    }
    Ok(())
}

/// The `d` of every Hayati pair of `model`, held at nominal and named with the `beta` that
/// replaces it.
pub(super) fn replaced_by_beta(model: &Model) -> Vec<FixedParameter> {
    model
        .pairs()
        .iter()
        .filter(|p| p.hayati)
        .filter_map(|p| {
            let d = p.dropped_d.as_ref()?;
            Some(FixedParameter {
                name: format!("{d}.d"),
                aliases: p
                    .beta_row
                    .as_ref()
                    .map(|b| vec![format!("{b}.beta")])
                    .unwrap_or_default(),
            })
        })
        .collect()
}

/// Gives every target that `cal` measures as a pose ([`Observation::TargetPose`]) its
/// orientation parameters ([`Model::add_target_orientation`]); targets measured as points
/// only get none, so a model of point data is unchanged.
pub(super) fn add_target_orientations(model: &mut Model, cal: &[Observed]) {
    for o in cal {
        if let Observation::TargetPose { target, .. } = o.observation {
            model.add_target_orientation(target);
        }
    }
}

/// The closed-form start of each oriented target's rotation on the tip, given the device
/// frame: `R_tipᵀ · R_measured` of its first pose sample (a target's rotation is rigid on the
/// tip, so one sample locates it up to the noise and the model's error).
pub(super) fn orient_targets(model: &mut Model, x: &[f64], cal: &[Observed]) {
    let mut done = vec![false; model.targets().len()];
    for o in cal {
        if let Observation::TargetPose { target, pose, .. } = &o.observation {
            if done.get(*target) == Some(&false) {
                let tip = model.tip_in(x, &o.q, model.target_chain(*target), o.session);
                model.set_target_rotation(*target, &(tip.rotation.inverse() * pose.rotation));
                done[*target] = true;
            }
        }
    }
}
