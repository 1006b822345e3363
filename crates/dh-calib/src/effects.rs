//! Non-geometric effects: what a rigid DH model lacks, as [`Effect`]s with labels.
//!
//! # Labels
//! Labels are part of the CLI and JSON contract (`J`, `K` are joint names):
//!
//! | label | change | parameters (unit) |
//! |---|---|---|
//! | `gear_ratio:J` | `theta_J += eps · q_J` | `gear_ratio:J` (rad/rad) |
//! | `gear_harmonic:J` | `theta_J += A sin q_J + B cos q_J` | `gear_harmonic:J.sin`, `.cos` (rad) |
//! | `gear_harmonic:J:2` | the same plus `A2 sin 2q_J + B2 cos 2q_J` | adds `.sin2`, `.cos2` (rad) |
//! | `gear_harmonic2:J` | `theta_J += A2 sin 2q_J + B2 cos 2q_J` (twice per turn alone) | `gear_harmonic2:J.sin2`, `.cos2` (rad) |
//! | `compliance:J` | `theta_J += c · tau_J(q)` (`d_J` for a prismatic joint) | `compliance:J` (rad/(N m), m/N) |
//! | `lateral_compliance:J` | `alpha_J += c · tau⊥_J(q)` | `lateral_compliance:J` (rad/(N m)) |
//! | `coupling:J:K` | `theta_J += k · q_K` | `coupling:J:K` (rad/rad) |
//! | `scale` | device positions `× (1 + s)` | `scale` (1) |
//! | `parallel_tilt:J` | the Hayati-Mirmirani `beta` of the near-parallel pair ending at `J` | `parallel_tilt:J` (rad) |
//! | `backlash:J` | `theta_J += b · tanh(tau_J / tau_0)` | `backlash:J` (rad) |
//! | `backlash_direction:J` | `theta_J += b · s_J`, `s_J` the sign of `J`'s last motion (`d_J` for a prismatic joint) | `backlash_direction:J` (rad; m) |
//! | `drift` | device positions `× (1 + c · t)`, `t` the pose's place in the sequence in `[0, 1]` | `drift` (1) |
//! | `thermal_growth` | robot positions `× (1 + k (1 − exp(−t/tau)))` about the base origin (every `a`, `d`, the tool and target offsets), `t` the sample's time since the set's first (s), or its place in the sequence without times | `thermal_growth.k` (1), `thermal_growth.ln_tau` (ln of tau in s) |
//! | `gravity_sag:J` | tip and targets move `c · abs(l_J)³` along gravity, `l_J` the tip's gravity lever arm about `J`'s axis (m) | `gravity_sag:J` (1/m², metres of sag at a 1 m lever arm) |
//!
//! `backlash_direction`, `drift` and `thermal_growth` depend on the order (or the time) of the
//! samples, not on the joint values alone: see [`crate::effects_order`] for `s_J` and `t`, and
//! [`crate::effects_thermal`] for the warm-up.
//!
//! `tau_J` is the gravity torque on joint `J` and `tau⊥_J` the one about the axis of its
//! `alpha` ([`crate::gravity`]), both computed **at the nominal geometry**: the torques of the
//! calibrated robot differ by the relative size of its geometric errors (a 1 mm error on a 1 m
//! arm changes a torque by 0.1 %), far below what a compliance estimate resolves, so the effect
//! stays linear in its parameter. `tau_0` of the backlash is 5 % of the joint's typical torque:
//! the gear flank changes over a small torque band instead of a discontinuous sign, which keeps
//! the model differentiable. A backlash is in the list for explicit use; automatic diagnosis
//! does not propose it (it is a rescaled compliance wherever the torque keeps its sign).
//!
//! `gravity_sag:J` needs the gravity direction alone (`--gravity`, else `-z` of the base link),
//! not inertials: see [`GravitySag`] for the lever arm's frames and where a joint has none.
//!
//! `parallel_tilt:J` applies only where the model holds a tilt at zero, i.e. for a pair within
//! [`crate::model::NEAR_PARALLEL`] of parallel that the geometric step does not already
//! parametrise with Hayati-Mirmirani ([`crate::model::Model::tilt_rows`]).
//!
//! # Layout
//! Labels, contexts and candidates are here; the effect models (gear harmonics, coupling,
//! scale, parallel tilt, gravity) are in `models`, re-exported here.

use std::sync::Arc;

use dh_core::{Convention, DhTable, JointKind};

use crate::fit::CalibError;
use crate::gravity::{GravityModel, TorqueAxis};
use crate::model::{Effect, EffectField, GearRatio};
use crate::tree::DhTree;

pub use crate::effect_label::EffectContext;
use crate::effect_label::{bad_label, expect_joint_names};

/// Parses an effect label (see the module docs) for a serial `table` without inertials.
///
/// # Errors
/// As [`parse_label_in`]; the gravity effects always fail (no inertials).
pub fn parse_label(label: &str, table: &DhTable) -> Result<Arc<dyn Effect>, CalibError> {
    parse_label_in(label, &EffectContext::serial(table))
}

/// Parses an effect label (see the module docs).
///
/// # Errors
/// [`CalibError::BadOption`] for an unknown kind, a missing or extra joint, a joint of the
/// wrong type (a gear effect on a prismatic joint), a gravity effect without inertials, or a
/// `parallel_tilt` on a joint that ends no consecutive pair; [`CalibError::MissingJoint`] for
/// a joint the robot does not have.
pub fn parse_label_in(label: &str, ctx: &EffectContext) -> Result<Arc<dyn Effect>, CalibError> {
    let parts: Vec<&str> = label.split(':').collect();
    let kind = parts[0];
    let args = &parts[1..];
    if let Some(e) = crate::effects_order::parse(label, kind, args, ctx) {
        return e;
    }
    let want = |n: usize| expect_joint_names(label, kind, args, n);
    let row = |name: &str| {
        ctx.tree
            .row_index(name)
            .ok_or_else(|| CalibError::MissingJoint { joint: name.into() })
    };
    let revolute = |name: &str| -> Result<usize, CalibError> {
        let r = row(name)?;
        if ctx.tree.rows()[r].kind != JointKind::Revolute {
            return Err(bad_label(
                label,
                format!("expected a revolute joint, found prismatic '{name}'"),
            ));
        }
        Ok(r)
    };
    let gravity = || {
        ctx.gravity.clone().ok_or_else(|| {
            bad_label(
                label,
                "expected link inertials (masses and centres) to compute gravity torques, found none",
            )
        })
    };
    match kind {
        "gear_ratio" => {
            want(1)?;
            revolute(args[0])?;
            Ok(Arc::new(GearRatio::new(&ctx.tree.joint_table(), args[0])?))
        }
        "gear_harmonic2" => {
            want(1)?;
            let r = revolute(args[0])?;
            Ok(Arc::new(GearHarmonic {
                joint: args[0].into(),
                row: r,
                harmonics: Harmonics::Second,
            }))
        }
        "gear_harmonic" => {
            let harmonics = match args {
                [_] => Harmonics::First,
                [_, "2"] => Harmonics::Both,
                _ => {
                    return Err(bad_label(
                        label,
                        format!(
                            "expected 'gear_harmonic:<joint>' or 'gear_harmonic:<joint>:2', found {} argument{}",
                            args.len(),
                            if args.len() == 1 { "" } else { "s" }
                        ),
                    ))
                }
            };
            let r = revolute(args[0])?;
            Ok(Arc::new(GearHarmonic {
                joint: args[0].into(),
                row: r,
                harmonics,
            }))
        }
        "compliance" | "lateral_compliance" | "backlash" => {
            want(1)?;
            let r = row(args[0])?;
            let g = gravity()?;
            let lateral = kind == "lateral_compliance";
            let prismatic = ctx.tree.rows()[r].kind == JointKind::Prismatic;
            if kind == "backlash" && prismatic {
                return Err(bad_label(
                    label,
                    format!("expected a revolute joint, found prismatic '{}'", args[0]),
                ));
            }
            if g.carried_mass(r) <= 0.0 {
                return Err(bad_label(
                    label,
                    format!("joint '{}' carries no mass in the inertials", args[0]),
                ));
            }
            Ok(Arc::new(Gravitational {
                kind: match kind {
                    "compliance" => GravityKind::Compliance,
                    "lateral_compliance" => GravityKind::Lateral,
                    _ => GravityKind::Backlash,
                },
                joint: args[0].into(),
                row: r,
                prismatic: prismatic && !lateral,
                gravity: g,
            }))
        }
        "coupling" => {
            want(2)?;
            let r = revolute(args[0])?;
            let k = row(args[1])?;
            if r == k {
                return Err(bad_label(
                    label,
                    "expected two different joints, found the same one twice (that is gear_ratio)",
                ));
            }
            Ok(Arc::new(Coupling {
                joint: args[0].into(),
                driver: args[1].into(),
                row: r,
                driver_row: k,
            }))
        }
        "gravity_sag" => {
            want(1)?;
            let r = revolute(args[0])?;
            Ok(Arc::new(GravitySag::new(label, ctx, args[0], r)?))
        }
        "scale" => {
            want(0)?;
            Ok(Arc::new(Scale))
        }
        "parallel_tilt" => {
            want(1)?;
            let j = row(args[0])?;
            let tilted = tilt_row(&ctx.tree, j).ok_or_else(|| {
                bad_label(
                    label,
                    format!(
                        "expected the later joint of a consecutive pair in one table, found '{}' (first of its table)",
                        args[0]
                    ),
                )
            })?;
            Ok(Arc::new(ParallelTilt {
                later: args[0].into(),
                joint: ctx.tree.rows()[tilted].name.clone(),
            }))
        }
        _ => Err(bad_label(
            label,
            format!(
                "expected one of gear_ratio, gear_harmonic, gear_harmonic2, compliance, lateral_compliance, coupling, scale, parallel_tilt, backlash, backlash_direction, drift, thermal_growth, gravity_sag; found '{kind}'"
            ),
        )),
    }
}

/// The row that carries the tilt of the pair ending at row `j` (`None` when `j` is first in
/// its table): the pair's first row in the standard convention, `j` itself in the modified.
fn tilt_row(tree: &DhTree, j: usize) -> Option<usize> {
    let (table, i) = tree.place(j);
    if i == 0 {
        return None;
    }
    let conv = match table {
        None => tree.trunk().convention,
        Some(b) => tree.branches()[b].table.convention,
    };
    Some(match conv {
        Convention::Standard => j - 1,
        Convention::Modified => j,
    })
}

/// The label of an effect (its kind and joints, as [`parse_label_in`] reads it).
pub fn label_of(effect: &dyn Effect) -> String {
    effect.label()
}

/// The candidates of automatic diagnosis, and the ones left out with the reason.
#[derive(Clone, Debug, Default)]
pub struct Candidates {
    /// The effects to score, in a fixed order.
    pub effects: Vec<Arc<dyn Effect>>,
    /// Kinds of candidates left out, with why (e.g. no inertials).
    pub skipped: Vec<String>,
}

/// Every applicable candidate for automatic diagnosis: per revolute joint `gear_ratio`,
/// `gear_harmonic`, `gear_harmonic2`, `gear_harmonic:J:2`, `gravity_sag` (of a serial robot,
/// where the joint's axis is not parallel to gravity: [`GravitySag`]; with inertials a rival
/// of the compliances, decided by the held-out RMS) and, with inertials, `compliance`
/// and `lateral_compliance` of joints that
/// gravity loads (typical torque above 1e-6 of the largest; `compliance` also for prismatic
/// joints); `coupling:J:K` for joints `K` within
/// two rows of `J` on one chain; per joint `backlash_direction` (the diagnosis holds it inert
/// where the joint reverses fewer than [`crate::effects_order::MIN_REVERSALS`] times in the
/// data); `scale`; `drift`; `thermal_growth`; `parallel_tilt`
/// for the rows in `tilt_rows`
/// ([`crate::model::Model::tilt_rows`]). Mimic rows are skipped (their driver's effects cover
/// them).
pub fn candidates(ctx: &EffectContext, tilt_rows: &[usize]) -> Candidates {
    let mut out = Candidates::default();
    let rows = ctx.tree.rows();
    let mut push = |label: String| {
        if let Ok(e) = parse_label_in(&label, ctx) {
            out.effects.push(e);
        }
    };
    for (j, r) in rows.iter().enumerate() {
        if r.mimic.is_some() {
            continue;
        }
        if r.kind == JointKind::Revolute {
            push(format!("gear_ratio:{}", r.name));
            push(format!("gear_harmonic:{}", r.name));
            push(format!("gear_harmonic2:{}", r.name));
            push(format!("gear_harmonic:{}:2", r.name));
        }
        push(format!("backlash_direction:{}", r.name));
        if let Some(g) = &ctx.gravity {
            let big = (0..rows.len())
                .flat_map(|k| {
                    [
                        g.torque_scale(k, TorqueAxis::Joint),
                        g.torque_scale(k, TorqueAxis::Lateral),
                    ]
                })
                .fold(0.0, f64::max);
            if g.torque_scale(j, TorqueAxis::Joint) > 1e-6 * big {
                push(format!("compliance:{}", r.name));
            }
            if g.torque_scale(j, TorqueAxis::Lateral) > 1e-6 * big {
                push(format!("lateral_compliance:{}", r.name));
            }
        }
        if r.kind == JointKind::Revolute {
            // Refused (and so skipped) where the joint's axis is parallel to gravity.
            push(format!("gravity_sag:{}", r.name));
        }
        if r.kind == JointKind::Revolute {
            for (k, o) in rows.iter().enumerate() {
                if k == j || o.mimic.is_some() {
                    continue;
                }
                let near = (0..ctx.tree.chain_count()).any(|c| {
                    let chain = ctx.tree.chain_rows(c);
                    match (
                        chain.iter().position(|&x| x == j),
                        chain.iter().position(|&x| x == k),
                    ) {
                        (Some(a), Some(b)) => a.abs_diff(b) <= 2,
                        _ => false,
                    }
                });
                if near {
                    push(format!("coupling:{}:{}", r.name, o.name));
                }
            }
        }
    }
    push("scale".into());
    push("drift".into());
    push(crate::effects_thermal::LABEL.into());
    for &t in tilt_rows {
        // The label names the later joint of the pair.
        let later = (0..rows.len()).find(|&j| tilt_row(&ctx.tree, j) == Some(t));
        if let Some(j) = later {
            push(format!("parallel_tilt:{}", rows[j].name));
        }
    }
    if ctx.gravity.is_none() {
        out.skipped.push(
            "compliance, lateral_compliance: no link inertials (masses and centres of mass), so \
             no gravity torques; give them to consider joint compliance"
                .into(),
        );
    }
    out
}

// The submodules import what they use through `use super::*`: the imports above and each
// other's items, re-exported here.
mod models;
pub use models::*;
mod sag;
pub use sag::{GravitySag, MIN_SAG_LEVER};
#[cfg(test)]
mod tests;
