//! Identifiability at an estimate ([`crate::fit::identifiability`]): which parameters the
//! data determine, the aliases of the others, and the estimates with standard errors and
//! the pose standard deviations (metres, radians).

use super::*;

/// Identifiability of `columns` at `x`; returns the free parameter indices and the fixed ones
/// (indices into the model's parameters). A combination is identifiable when its singular value
/// of the scaled Jacobian is above `rank_tolerance` times the largest and moves the points by at
/// least [`FitOptions::min_sensitivity`] RMS per unit of scaled parameter.
pub(crate) fn identify(
    model: &Model,
    cal: &[Observed],
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    options: &CalibrationOptions,
) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
    let problem = ModelProblem {
        model,
        observations: cal,
    };
    identify_in(&problem, model, x, columns, scales, options)
}

/// [`identify`] over the samples of `problem` (all of them, or a subset) of `model`.
pub(super) fn identify_in<P: fit::Problem>(
    problem: &P,
    model: &Model,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    options: &CalibrationOptions,
) -> Result<(Vec<usize>, Vec<fit::Fixed>), CalibError> {
    let (free, fixed, _) = identify_factored_in(problem, model, x, columns, scales, options)?;
    Ok((free, fixed))
}

/// [`identify_in`], with the factor of `columns` at `x` it decided on ([`fit::factor_by_qr`]
/// of `problem`: the columns are asked about because some may be aliased, where the Gram
/// matrix of a large problem is refused): a fit of the same columns from `x` starts from it
/// ([`fit::solve_from`]).
pub(super) fn identify_factored_in<P: fit::Problem>(
    problem: &P,
    model: &Model,
    x: &[f64],
    columns: &[usize],
    scales: &[f64],
    options: &CalibrationOptions,
) -> Result<(Vec<usize>, Vec<fit::Fixed>, fit::Factor), CalibError> {
    let f = fit::factor_by_qr(problem, x, columns, scales)?;
    let prio_all = model.priorities();
    let prio: Vec<u32> = columns.iter().map(|&c| prio_all[c]).collect();
    // The sensitivity floor is an RMS over points: the factor's singular values are sums in
    // quadrature over all rows, three per point.
    let floor = options.fit.min_sensitivity * (f.rows as f64 / 3.0).sqrt();
    let id = fit::identifiability_above(
        &f.r,
        &vec![1.0; columns.len()],
        &prio,
        options.fit.rank_tolerance,
        floor,
    )?;
    let free = id.free.iter().map(|&i| columns[i]).collect();
    let fixed = id
        .fixed
        .into_iter()
        .map(|f| {
            let mut combination = vec![0.0; model.parameter_count()];
            for (i, c) in f.combination.iter().enumerate() {
                // Back to parameter units: the factor was of scaled columns.
                combination[columns[i]] = c * scales[columns[i]] / scales[columns[f.index]];
            }
            fit::Fixed {
                index: columns[f.index],
                aliases: f.aliases.iter().map(|&a| columns[a]).collect(),
                combination,
            }
        })
        .collect();
    Ok((free, fixed, f))
}

/// Parameter estimates in the report's layout.
pub(super) fn estimates(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    device_nominal: Isometry3<f64>,
    targets_nominal: &[Vector3<f64>],
) -> Vec<ParameterEstimate> {
    let params = model.parameters();
    let nominal = model.nominal();
    let position = |c: usize| fit.free.iter().position(|&f| f == c);
    let mut out = Vec::with_capacity(params.len());
    let mut done_blocks: Vec<Block> = Vec::new();
    for (c, p) in params.iter().enumerate() {
        match p.block {
            Block::Device | Block::Session(_) | Block::Base | Block::Tool | Block::Mount(_) => {
                if done_blocks.contains(&p.block) {
                    continue;
                }
                done_blocks.push(p.block);
                let idx = model.indices(|b| b == p.block);
                let nom = match p.block {
                    Block::Device => xyz_rpy(&device_nominal),
                    // The reference after the `nominal` step's rebase.
                    Block::Session(_) => xyz_rpy(&model.pose_at(&vec![0.0; x.len()], p.block)),
                    Block::Base => xyz_rpy(&nominal.base),
                    Block::Mount(b) => model.tree().branches().get(b).map_or_else(
                        || xyz_rpy(&Isometry3::identity()),
                        |br| xyz_rpy(&br.table.base),
                    ),
                    _ => xyz_rpy(&nominal.tool),
                };
                let est = xyz_rpy(&model.pose_at(x, p.block));
                let std = pose_std(model, x, fit, p.block, &idx);
                for (k, &i) in idx.iter().enumerate() {
                    out.push(ParameterEstimate {
                        name: params[i].name.clone(),
                        nominal: nom[k],
                        estimate: est[k],
                        std_error: std.as_ref().map(|s| s[k]),
                        free: position(i).is_some(),
                    });
                }
            }
            Block::Joint(r) => {
                let row = &nominal.rows[r];
                let nom = match p.field {
                    crate::model::Field::A => row.a,
                    crate::model::Field::Alpha => row.alpha,
                    crate::model::Field::D => row.d,
                    crate::model::Field::Theta => row.theta,
                    crate::model::Field::Beta => row.beta,
                    _ => 0.0,
                };
                out.push(ParameterEstimate {
                    name: p.name.clone(),
                    nominal: nom,
                    estimate: nom + x[c],
                    std_error: fit.std_errors[c],
                    free: position(c).is_some(),
                });
            }
            Block::Target(k) => {
                let axis = match p.field {
                    crate::model::Field::X => 0,
                    crate::model::Field::Y => 1,
                    _ => 2,
                };
                out.push(ParameterEstimate {
                    name: p.name.clone(),
                    nominal: targets_nominal.get(k).map_or(0.0, |t| t[axis]),
                    estimate: model.target_at(x, k)[axis],
                    std_error: fit.std_errors[c],
                    free: position(c).is_some(),
                });
            }
            Block::Effect(_) => out.push(ParameterEstimate {
                name: p.name.clone(),
                nominal: 0.0,
                estimate: x[c],
                std_error: fit.std_errors[c],
                free: position(c).is_some(),
            }),
        }
    }
    out
}

/// Standard errors of a pose block's `x y z rx ry rz` (absolute, roll-pitch-yaw), propagated
/// from the covariance of its six small-motion parameters by a central-difference Jacobian.
pub(super) fn pose_std(
    model: &Model,
    x: &[f64],
    fit: &FitOutcome,
    block: Block,
    idx: &[usize],
) -> Option<[f64; 6]> {
    let cov = fit.covariance.as_ref()?;
    let pos: Vec<Option<usize>> = idx
        .iter()
        .map(|&i| fit.free.iter().position(|&f| f == i))
        .collect();
    if pos.iter().all(Option::is_none) {
        return None;
    }
    let h = 1e-6;
    let mut g = DMatrix::zeros(6, idx.len());
    let mut xp = x.to_vec();
    for (k, &i) in idx.iter().enumerate() {
        xp[i] = x[i] + h;
        let a = xyz_rpy(&model.pose_at(&xp, block));
        xp[i] = x[i] - h;
        let b = xyz_rpy(&model.pose_at(&xp, block));
        xp[i] = x[i];
        for r in 0..6 {
            let mut d = a[r] - b[r];
            if r >= 3 {
                // Angles wrap at ±pi.
                d = (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI;
            }
            g[(r, k)] = d / (2.0 * h);
        }
    }
    let c = DMatrix::from_fn(idx.len(), idx.len(), |a, b| match (pos[a], pos[b]) {
        (Some(i), Some(j)) => cov[(i, j)],
        _ => 0.0,
    });
    let v = &g * c * g.transpose();
    Some(std::array::from_fn(|r| v[(r, r)].max(0.0).sqrt()))
}
