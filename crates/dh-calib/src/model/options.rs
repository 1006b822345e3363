//! Options of a model and how each pair of consecutive joints is parametrised (plain DH or
//! Hayati-Mirmirani, see the parent module; angles in radians).

use dh_core::{Convention, DhTable};
use nalgebra::Vector3;

use crate::fit::CalibError;

/// How one pair of consecutive joints is parametrised.
#[derive(Clone, Debug, PartialEq)]
pub struct PairParametrisation {
    /// The earlier joint.
    pub first: String,
    /// The later joint.
    pub second: String,
    /// Angle between the two axes at the nominal zero pose, folded to `[0, pi/2]` (radians).
    pub angle: f64,
    /// `true` when the pair uses Hayati-Mirmirani (`beta` instead of a `d` error).
    pub hayati: bool,
    /// The row whose `beta` parameter the pair adds (when `hayati`).
    pub beta_row: Option<String>,
    /// The row whose `d` error the pair drops (when `hayati`).
    pub dropped_d: Option<String>,
}

/// Options of [`Model::new`](super::Model::new).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelOptions {
    /// Pairs of consecutive axes within this angle of parallel (radians) at the nominal zero
    /// pose use Hayati-Mirmirani. Default 1 degree.
    pub hayati_threshold: f64,
    /// Characteristic length (metres) that scales angle columns; `None` uses
    /// [`DhTable::size`].
    pub length_scale: Option<f64>,
    /// Metres per radian of orientation residual for pose measurements; `None` uses the
    /// length scale.
    pub orientation_scale: Option<f64>,
}

impl ModelOptions {
    /// Default Hayati threshold: 1 degree.
    pub const DEFAULT_HAYATI_THRESHOLD: f64 = std::f64::consts::PI / 180.0;
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self {
            hayati_threshold: Self::DEFAULT_HAYATI_THRESHOLD,
            length_scale: None,
            orientation_scale: None,
        }
    }
}

/// Consecutive axes within this angle of parallel (radians, 5 degrees) that do not use
/// Hayati-Mirmirani get a tilt about `y` held at zero, which an [`EffectField::Beta`](super::EffectField::Beta) effect
/// (the `parallel_tilt` candidate) can free.
pub const NEAR_PARALLEL: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// Per table row: does it carry a Hayati `beta` parameter, a zero tilt placeholder, and is
/// its `d` error dropped.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RowPlan {
    pub(super) beta: bool,
    pub(super) placeholder: bool,
    pub(super) drop_d: bool,
}

pub(super) fn plan_table(
    table: &DhTable,
    threshold: f64,
) -> Result<(Vec<PairParametrisation>, Vec<RowPlan>), CalibError> {
    let n = table.rows.len();
    let pairs = classify_pairs(table, threshold)?;
    let mut plan = vec![RowPlan::default(); n];
    for (i, p) in pairs.iter().enumerate() {
        let beta_row = match table.convention {
            Convention::Standard => i,
            Convention::Modified => i + 1,
        };
        if p.hayati {
            plan[i].drop_d = true;
            plan[beta_row].beta = true;
        } else if p.angle <= NEAR_PARALLEL {
            plan[beta_row].placeholder = true;
        }
    }
    Ok((pairs, plan))
}

fn classify_pairs(table: &DhTable, threshold: f64) -> Result<Vec<PairParametrisation>, CalibError> {
    let n = table.rows.len();
    let frames = table.frames(&vec![0.0; n])?;
    let shift = usize::from(table.convention == Convention::Modified);
    let axis = |i: usize| frames[i + shift].rotation * Vector3::z();
    let mut out = Vec::new();
    for i in 0..n.saturating_sub(1) {
        let (u, w) = (axis(i), axis(i + 1));
        let angle = u.cross(&w).norm().atan2(u.dot(&w).abs());
        let hayati = angle <= threshold;
        let beta_row = match table.convention {
            Convention::Standard => i,
            Convention::Modified => i + 1,
        };
        out.push(PairParametrisation {
            first: table.rows[i].name.clone(),
            second: table.rows[i + 1].name.clone(),
            angle,
            hayati,
            beta_row: hayati.then(|| table.rows[beta_row].name.clone()),
            dropped_d: hayati.then(|| table.rows[i].name.clone()),
        });
    }
    Ok(out)
}
