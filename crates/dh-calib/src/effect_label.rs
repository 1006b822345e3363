//! What reading an effect label needs, shared by [`crate::effects`] (geometric, gear and
//! gravity effects) and [`crate::effects_order`] (effects of the measurement sequence): the
//! robot and its masses ([`EffectContext`]) and the errors of a label that does not read.

use std::sync::Arc;

use dh_core::DhTable;

use crate::fit::CalibError;
use crate::gravity::GravityModel;
use crate::tree::DhTree;

/// What parsing labels and enumerating candidates need: the robot (its rows give the layout
/// of `q`) and, for the gravity effects, its masses.
#[derive(Clone, Debug)]
pub struct EffectContext {
    /// The robot (a trunk only for a serial robot).
    pub tree: DhTree,
    /// Gravity torques; `None` when the robot has no inertials.
    pub gravity: Option<Arc<GravityModel>>,
    /// Gravity in the base link frame (m/s²) for the effects that need its direction alone
    /// (`gravity_sag`) when there are no inertials; [`EffectContext::gravity`]'s own vector
    /// is used when there are. Default [`GravityModel::default_gravity`].
    pub gravity_vector: nalgebra::Vector3<f64>,
}

impl EffectContext {
    /// A serial robot without inertials.
    pub fn serial(table: &DhTable) -> Self {
        Self {
            tree: DhTree::serial(table),
            gravity: None,
            gravity_vector: GravityModel::default_gravity(),
        }
    }
}

/// An effect label that does not read, and why.
pub(crate) fn bad_label(label: &str, reason: impl Into<String>) -> CalibError {
    CalibError::BadOption {
        what: format!("effect '{label}'"),
        reason: reason.into(),
    }
}

/// Refuses a label of kind `kind` unless it has exactly `n` non-empty joint names `args`.
pub(crate) fn expect_joint_names(
    label: &str,
    kind: &str,
    args: &[&str],
    n: usize,
) -> Result<(), CalibError> {
    if args.len() == n && args.iter().all(|a| !a.is_empty()) {
        Ok(())
    } else {
        Err(bad_label(
            label,
            format!(
                "expected '{kind}' with {n} joint name{}, found {} argument{}",
                if n == 1 { "" } else { "s" },
                args.len(),
                if args.len() == 1 { "" } else { "s" }
            ),
        ))
    }
}
