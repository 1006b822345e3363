//! Checking a sheet's numbers on the way to SI units (metres, radians): rows (names, finite
//! and bounded values, limits, mimics), poses, couplings and effects. Shared by the serial and
//! the tree sheet, whose `origin` adds the line and branch.

use dh_core::pose::from_xyz_rpy;
use dh_core::{DhRow, JointKind, Limits, Mimic};
use nalgebra::Isometry3;

use super::{EffectDoc, JointDoc, JointType, PoseDoc};
use crate::error::{Result, SheetError};
use crate::text::{escape, is_spoofing};
use crate::units::{AngleUnit, LengthUnit};

/// Largest magnitude of a sheet value, in its own unit: an overflow guard (found by fuzzing the
/// URDF path: a finite 1e306 m became infinite in millimetres). Far beyond anything `extract`
/// writes (an ill-conditioned common normal of URDF axes within 1e9 m stays below 1e25 m, 1e28
/// mm), and far from overflow in any unit conversion or forward kinematics.
const MAX_MAGNITUDE: f64 = 1e30;

/// Largest magnitude of a sheet value in metres or radians: a thousandth of
/// [`MAX_MAGNITUDE`], so that whatever a sheet holds can be written in any unit (mm, deg: at
/// most x1000) and read back.
const MAX_SI_MAGNITUDE: f64 = 1e27;

/// Is `v` (in a unit of `scale` metres or radians) beyond what a sheet may hold?
fn too_large(v: f64, scale: f64) -> bool {
    v.abs() > MAX_MAGNITUDE || (v * scale).abs() > MAX_SI_MAGNITUDE
}

/// Largest magnitude of a DH angle or `rpy` angle (radians): past it a double wraps the angle
/// to the circle with an error above 1e-10 rad, and 9.9e26 rad has no angle left in it at all.
/// Joint limits may be larger (they only bound the joint values drawn).
const MAX_ANGLE: f64 = 1e6;

/// Lengths beyond this in a sheet that says metres are almost surely millimetres (m).
const SUSPICIOUS_METRES: f64 = 20.0;

/// Row `j` of a sheet in SI units; suspicious units add to `warnings`. `origin` prefixes
/// every message (the file, and for a tree sheet the line and branch).
///
/// # Errors
/// A control character in the name, a non-finite or huge value, limits out of order or
/// half given, a bad mimic multiplier or offset.
pub(crate) fn row_of(
    j: &JointDoc,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
    origin: &str,
    warnings: &mut Vec<String>,
) -> Result<DhRow> {
    let (lu, au) = (length_unit.metres(), angle_unit.radians());
    let bad = |problem: String| SheetError::BadJoint {
        origin: origin.into(),
        joint: j.name.clone(),
        problem,
    };
    if j.name.trim().is_empty() {
        return Err(bad("expected a name, found a blank one".into()));
    }
    if let Some((k, c)) = j.name.chars().enumerate().find(|(_, c)| is_spoofing(*c)) {
        // As the URDF reader: such a name corrupts tables, CSV and terminals (and a bidi
        // override reorders what they show).
        return Err(SheetError::BadJoint {
            origin: origin.into(),
            joint: escape(&j.name).into_owned(),
            problem: format!(
                "expected a name without control or bidi characters, found U+{:04X} at \
                 character {}",
                u32::from(c),
                k + 1
            ),
        });
    }
    let limit_scale = if j.kind == JointType::Prismatic {
        lu
    } else {
        au
    };
    for (field, v, scale) in [
        ("a", j.a, lu),
        ("alpha", j.alpha, au),
        ("d", j.d, lu),
        ("theta", j.theta, au),
    ]
    .into_iter()
    .chain(j.beta.map(|v| ("beta", v, au)))
    .chain(j.lower.map(|v| ("lower", v, limit_scale)))
    .chain(j.upper.map(|v| ("upper", v, limit_scale)))
    {
        if !v.is_finite() {
            return Err(bad(format!("{field} must be a finite number, found {v}")));
        }
        if too_large(v, scale) {
            return Err(bad(format!(
                "{field}: expected a magnitude of at most 1e30 (1e27 m or rad), found {v:e}"
            )));
        }
        if matches!(field, "alpha" | "theta") && (v * scale).abs() > MAX_ANGLE {
            return Err(bad(format!(
                "{field}: expected an angle of at most {MAX_ANGLE:e} rad, found {v:e} {} (a \
                 double holds no angle that large)",
                angle_unit.symbol()
            )));
        }
    }
    if let Some(b) = j.beta {
        if (b * au).abs() > MAX_TILT {
            return Err(bad(format!(
                "beta: expected a tilt of at most 90 degrees, found {b} {}",
                angle_unit.symbol()
            )));
        }
    }
    let kind = match j.kind {
        JointType::Revolute => JointKind::Revolute,
        JointType::Prismatic => JointKind::Prismatic,
    };
    let limit_unit = if kind == JointKind::Prismatic { lu } else { au };
    let limits = match (j.lower, j.upper) {
        (Some(l), Some(u)) if l > u => {
            return Err(bad(format!("lower limit {l} is above upper limit {u}")));
        }
        (Some(l), Some(u)) => Some(Limits {
            lower: l * limit_unit,
            upper: u * limit_unit,
        }),
        (None, None) => None,
        _ => return Err(bad("give both 'lower' and 'upper', or neither".into())),
    };
    if length_unit == LengthUnit::M
        && (j.a.abs() > SUSPICIOUS_METRES || j.d.abs() > SUSPICIOUS_METRES)
    {
        warnings.push(format!(
            "{origin}: joint '{}': a = {}, d = {} with length_unit m looks like millimetres; set length_unit: mm if so",
            j.name, j.a, j.d
        ));
    }
    if angle_unit == AngleUnit::Rad
        && (j.alpha.abs() > 2.0 * std::f64::consts::PI + 1e-9
            || j.theta.abs() > 2.0 * std::f64::consts::PI + 1e-9)
    {
        warnings.push(format!(
            "{origin}: joint '{}': alpha = {}, theta = {} with angle_unit rad looks like degrees; set angle_unit: deg if so",
            j.name, j.alpha, j.theta
        ));
    }
    let alpha = angle_of(j.alpha, angle_unit, "alpha", &j.name, origin, warnings);
    let theta = angle_of(j.theta, angle_unit, "theta", &j.name, origin, warnings);
    let mimic = match &j.mimic {
        Some(m) => {
            if !m.multiplier.is_finite()
                || !m.offset.is_finite()
                || m.multiplier.abs() > MAX_MAGNITUDE
                || m.offset.abs() > MAX_MAGNITUDE
            {
                return Err(bad(
                    "mimic multiplier and offset must be finite, of magnitude at most 1e30".into(),
                ));
            }
            Some(Mimic {
                joint: m.joint.clone(),
                multiplier: m.multiplier,
                offset: m.offset * limit_unit,
            })
        }
        None => None,
    };
    Ok(DhRow {
        name: j.name.clone(),
        kind,
        a: j.a * lu,
        alpha,
        d: j.d * lu,
        theta,
        beta: j.beta.map_or(0.0, |b| b * au),
        limits,
        mimic,
    })
}

/// `2 pi - TAU`: the part of a turn a double's `TAU` leaves out (radians), so that a wrap by
/// `k` turns subtracts `k (TAU + TAU_LO)`, within 1e-16 rad of `k` exact turns for every angle
/// a sheet may hold ([`MAX_ANGLE`]; Cody and Waite's two-part constant).
const TAU_LO: f64 = 2.449_293_598_294_706_4e-16;

/// A DH angle (`alpha`, `theta`) of a sheet in radians, wrapped to `(-pi, pi]` when it is more
/// than a turn (`|v| > 360°`, `|v| > 2 pi rad`), with a warning naming the joint and field:
/// a sheet's angle is an angle, and a written table holds it to 1e-12 rad, which a value of
/// 999999 rad cannot be written to (the proofs of `convert` and `to-urdf` failed on it).
/// Angles within a turn are kept as given (a sheet's 270° or -180° stays so). Degrees wrap
/// exactly (`rem_euclid(360)`); radians within 1e-16 rad of the exact wrap ([`TAU_LO`]).
pub(crate) fn angle_of(
    v: f64,
    unit: AngleUnit,
    field: &str,
    joint: &str,
    origin: &str,
    warnings: &mut Vec<String>,
) -> f64 {
    use std::f64::consts::{PI, TAU};
    let wrapped = match unit {
        AngleUnit::Deg if v.abs() > 360.0 => {
            let r = v.rem_euclid(360.0);
            (if r > 180.0 { r - 360.0 } else { r }) * unit.radians()
        }
        AngleUnit::Rad if v.abs() > TAU => {
            let k = (v / TAU).round();
            let mut r = (-k).mul_add(TAU_LO, (-k).mul_add(TAU, v));
            if r > PI {
                r = (r - TAU) - TAU_LO;
            } else if r <= -PI {
                r = (r + TAU) + TAU_LO;
            }
            r
        }
        _ => return v * unit.radians(),
    };
    let shown = match unit {
        AngleUnit::Deg => wrapped.to_degrees(),
        AngleUnit::Rad => wrapped,
    };
    warnings.push(format!(
        "{origin}: joint '{joint}': {field} = {v} {} is more than a turn: read as {shown:.12} {} (the same angle, within half a turn)",
        unit.symbol(),
        unit.symbol()
    ));
    wrapped
}

/// The largest tilt a row may carry (radians): a Hayati tilt is a small correction of a
/// nearly parallel pair, and beyond a right angle the pair is no such pair.
const MAX_TILT: f64 = std::f64::consts::FRAC_PI_2;

/// Checks a sheet's `effects` (finite values and uncertainties, distinct non-empty names).
///
/// # Errors
/// A bad value, uncertainty or name, naming the effect.
pub(crate) fn effects_of(given: Option<Vec<EffectDoc>>, origin: &str) -> Result<Vec<EffectDoc>> {
    let effects = given.unwrap_or_default();
    let mut seen = std::collections::HashSet::new();
    for e in &effects {
        let bad = |problem: String| SheetError::BadEffects {
            origin: origin.into(),
            problem,
        };
        // Control and bidi characters as for joint names: the name is printed in tables.
        if e.name.is_empty() || e.name.chars().any(is_spoofing) {
            return Err(bad(format!(
                "expected a printable effect name, found '{}'",
                escape(&e.name)
            )));
        }
        if !seen.insert(e.name.as_str()) {
            return Err(bad(format!("'{}' appears twice", e.name)));
        }
        if !(e.value.is_finite() && e.value.abs() <= MAX_MAGNITUDE) {
            return Err(bad(format!(
                "'{}': expected a finite value, found {}",
                e.name, e.value
            )));
        }
        if let Some(s) = e.std_error {
            if !(s.is_finite() && s >= 0.0) {
                return Err(bad(format!(
                    "'{}': expected a finite std_error >= 0, found {s}",
                    e.name
                )));
            }
        }
    }
    Ok(effects)
}

/// A sheet's pose in SI units (identity when absent); `what` names it in errors.
///
/// # Errors
/// Non-finite or huge numbers.
pub(crate) fn pose_of(
    p: Option<&PoseDoc>,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
    origin: &str,
    what: &str,
) -> Result<Isometry3<f64>> {
    let (lu, au) = (length_unit.metres(), angle_unit.radians());
    let bad = |problem: String| SheetError::BadPose {
        origin: origin.into(),
        what: what.into(),
        problem,
    };
    match p {
        None => Ok(Isometry3::identity()),
        Some(p) => {
            if p.xyz.iter().chain(&p.rpy).any(|v| !v.is_finite()) {
                return Err(bad("xyz and rpy must be finite numbers".into()));
            }
            if let Some(v) = p.xyz.iter().find(|v| too_large(**v, lu)) {
                return Err(bad(format!(
                    "xyz: expected a magnitude of at most 1e30 (1e27 m), found {v:e}"
                )));
            }
            if let Some(v) = p.rpy.iter().find(|v| (**v * au).abs() > MAX_ANGLE) {
                return Err(bad(format!(
                    "rpy: expected an angle of at most {MAX_ANGLE:e} rad, found {v:e} {} (a \
                     double holds no angle that large)",
                    angle_unit.symbol()
                )));
            }
            Ok(from_xyz_rpy(p.xyz.map(|v| v * lu), p.rpy.map(|v| v * au)))
        }
    }
}

/// Refuses a row that mimics itself and rows whose mimics form a cycle (each follows the next,
/// the last the first: no joint of the cycle moves on its own, as the URDF reader refuses);
/// warns of a mimic whose driver is no row of `rows`.
///
/// # Errors
/// A row that mimics itself, or the first row (in order) of a cycle, naming the cycle.
pub(crate) fn check_mimics(rows: &[DhRow], origin: &str, warnings: &mut Vec<String>) -> Result<()> {
    check_mimic_cycles(rows, origin)?;
    for r in rows {
        let Some(m) = &r.mimic else { continue };
        if m.joint == r.name {
            return Err(SheetError::BadJoint {
                origin: origin.into(),
                joint: r.name.clone(),
                problem: "mimic: expected another joint to follow, found itself".into(),
            });
        }
        if !rows.iter().any(|d| d.name == m.joint) {
            warnings.push(format!(
                "{origin}: joint '{}': mimic: follows '{}', which is no joint of the sheet (joints: {}); it moves on its own here",
                r.name,
                m.joint,
                rows.iter().map(|d| format!("'{}'", d.name)).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    Ok(())
}

/// The first mimic cycle of `rows`, as [`check_mimics`] refuses it. Each row is walked once
/// (a 100 000-joint mimic chain is a linear pass): a walk stops at a row already finished.
fn check_mimic_cycles(rows: &[DhRow], origin: &str) -> Result<()> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        New,
        OnWalk,
        Done,
    }
    let index: std::collections::HashMap<&str, usize> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| (r.name.as_str(), i))
        .collect();
    let driver = |i: usize| {
        rows[i]
            .mimic
            .as_ref()
            .and_then(|m| index.get(m.joint.as_str()).copied())
            // A row that follows itself is refused by its own message.
            .filter(|&d| d != i)
    };
    let mut state = vec![State::New; rows.len()];
    let mut walk: Vec<usize> = Vec::new();
    for start in 0..rows.len() {
        walk.clear();
        let mut at = Some(start);
        while let Some(i) = at {
            match state[i] {
                State::Done => break,
                State::OnWalk => {
                    let first = walk.iter().position(|&w| w == i).unwrap_or(0);
                    let mut names: Vec<&str> = walk[first..]
                        .iter()
                        .map(|&w| rows[w].name.as_str())
                        .collect();
                    names.push(rows[i].name.as_str());
                    return Err(SheetError::BadJoint {
                        origin: origin.into(),
                        joint: rows[i].name.clone(),
                        problem: format!(
                            "mimic: expected drivers that end at a joint that mimics none, found \
                             a cycle {}",
                            names.join(" -> ")
                        ),
                    });
                }
                State::New => {
                    state[i] = State::OnWalk;
                    walk.push(i);
                    at = driver(i);
                }
            }
        }
        for &w in &walk {
            state[w] = State::Done;
        }
    }
    Ok(())
}

/// The `coupled` key of a sheet: `{joint: {driver: coefficient}}`.
pub type CoupledDoc = std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>>;

/// A coupled joint and its `(driver, coefficient)` terms.
pub type Coupled = (String, Vec<(String, f64)>);

/// Coupled joints (see [`SheetDoc::coupled`]) checked against `rows`, in row order.
///
/// # Errors
/// A coupled joint or driver that is no row, a coupled joint with a mimic, no driver, a
/// non-finite coefficient.
pub(crate) fn coupled_of(
    given: Option<&CoupledDoc>,
    rows: &[DhRow],
    origin: &str,
) -> Result<Vec<Coupled>> {
    let bad = |problem: String| SheetError::BadCoupling {
        origin: origin.into(),
        problem,
    };
    let mut coupled = Vec::new();
    for (joint, terms) in given.into_iter().flatten() {
        let row = rows.iter().find(|r| &r.name == joint);
        match row {
            None => return Err(bad(format!("'{joint}' is no joint of the sheet"))),
            Some(r) if r.mimic.is_some() => {
                return Err(bad(format!(
                    "joint '{joint}' also has a mimic; give one of them"
                )))
            }
            Some(_) => {}
        }
        if terms.is_empty() {
            return Err(bad(format!(
                "joint '{joint}': expected at least one driver"
            )));
        }
        for (driver, c) in terms {
            if !c.is_finite() {
                return Err(bad(format!(
                    "joint '{joint}': coefficient of '{driver}' must be finite, found {c}"
                )));
            }
            if driver != joint && !rows.iter().any(|r| &r.name == driver) {
                return Err(bad(format!(
                    "joint '{joint}': driver '{driver}' is no joint of the sheet"
                )));
            }
        }
        coupled.push((
            joint.clone(),
            terms.iter().map(|(d, c)| (d.clone(), *c)).collect(),
        ));
    }
    let order = |j: &str| rows.iter().position(|r| r.name == j);
    coupled.sort_by_key(|(j, _)| order(j));
    Ok(coupled)
}
