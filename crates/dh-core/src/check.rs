//! Does a sheet describe the robot? The two independent answers combined into one verdict.
//!
//! 1. The row-by-row walk of [`crate::equivalence`] sees through the representation freedoms
//!    and names every parameter that differs (and every joint whose type differs).
//! 2. The sheet taken literally ([`crate::literal`]): its free base and tool fitted, the largest
//!    tip deviation from the robot's own forward kinematics.
//!
//! The invariant: a sheet [`SheetCheck::matches`] only when the walk finds no difference **and**
//! the literal deviation is within the tolerances, [`FkBound`]: orientation within `angular`
//! radians, position within `linear + angular × size` metres (an angle within the tolerance,
//! such as a URDF's `rpy="1.5708"`, moves a point at the chain's size by `angular × size`).
//! Should the walk find nothing while the literal comparison disagrees, the verdict carries a
//! [`Parameter::FkPosition`] / [`Parameter::FkOrientation`] difference, so no caller can print
//! a match with a differing FK.

use nalgebra::Isometry3;

use crate::equivalence::{compare_tables, Difference, Freedom, Parameter};
use crate::literal::{fit_literal, LiteralFit};
use crate::table::DhTable;
use crate::{CoreError, Tolerance};

/// What the sheet taken literally may deviate from the robot and still match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FkBound {
    /// Tip position (metres): `linear + angular × size`.
    pub position: f64,
    /// Tip orientation (radians): `angular`.
    pub orientation: f64,
}

impl FkBound {
    /// The bound for tolerances `tol` on a chain of `size` metres ([`DhTable::size`]).
    pub fn new(tol: Tolerance, size: f64) -> Self {
        Self {
            position: tol.linear + tol.angular * size,
            orientation: tol.angular,
        }
    }
}

/// The verdict of [`check_sheet`].
#[derive(Clone, Debug, PartialEq)]
pub struct SheetCheck {
    differences: Vec<Difference>,
    literal: LiteralFit,
    bound: FkBound,
}

impl SheetCheck {
    /// Combines the walk's differences with the literal fit, adding the FK differences the
    /// invariant asks for (see the module docs).
    pub fn new(mut differences: Vec<Difference>, literal: LiteralFit, bound: FkBound) -> Self {
        if differences.is_empty() {
            let dev = &literal.deviation;
            if beyond(dev.max_position_error, bound.position) {
                differences.push(Difference {
                    row: None,
                    parameter: Parameter::FkPosition,
                    reference: dev.max_position_error,
                    sheet: 0.0,
                    aliases: vec![],
                });
            }
            if beyond(dev.max_orientation_error, bound.orientation) {
                differences.push(Difference {
                    row: None,
                    parameter: Parameter::FkOrientation,
                    reference: dev.max_orientation_error,
                    sheet: 0.0,
                    aliases: vec![],
                });
            }
        }
        Self {
            differences,
            literal,
            bound,
        }
    }

    /// The sheet describes the robot: no difference, and the literal deviation within the
    /// tolerances.
    pub fn matches(&self) -> bool {
        let dev = &self.literal.deviation;
        self.differences.is_empty()
            && dev.max_position_error <= self.bound.position
            && dev.max_orientation_error <= self.bound.orientation
    }

    /// The bound the literal deviation is held to.
    pub fn bound(&self) -> FkBound {
        self.bound
    }

    /// Every difference (the walk's, then any FK difference).
    pub fn differences(&self) -> &[Difference] {
        &self.differences
    }

    /// The sheet taken literally, its free base and tool fitted.
    pub fn literal(&self) -> &LiteralFit {
        &self.literal
    }
}

/// `value` exceeds `bound`, or is NaN (which must never pass as small).
fn beyond(value: f64, bound: f64) -> bool {
    use std::cmp::Ordering::{Equal, Less};
    !matches!(value.partial_cmp(&bound), Some(Less | Equal))
}

/// Checks `sheet` against a robot given by `reference` (a table known to be exact for it, e.g.
/// extracted from its URDF, in any convention) and `oracle` (the tip link's pose in the base
/// link at joint values `q`). Both tables have one row per moving joint, in chain order.
///
/// # Errors
/// [`CoreError::JointCount`] when the row counts differ (callers report that as a difference
/// of their own before calling).
pub fn check_sheet<F>(
    reference: &DhTable,
    sheet: &DhTable,
    freedom: Freedom,
    tol: Tolerance,
    oracle: F,
) -> Result<SheetCheck, CoreError>
where
    F: FnMut(&[f64]) -> Isometry3<f64>,
{
    let literal = fit_literal(sheet, reference, freedom, oracle, tol)?;
    let walk = compare_tables(reference, sheet, freedom, tol);
    let bound = FkBound::new(tol, reference.size());
    Ok(SheetCheck::new(walk.differences, literal, bound))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verify::Deviation;

    fn literal(position: f64, orientation: f64) -> LiteralFit {
        LiteralFit {
            base: Isometry3::identity(),
            tool: Isometry3::identity(),
            deviation: Deviation {
                samples: 500,
                max_position_error: position,
                max_orientation_error: orientation,
            },
        }
    }

    /// No difference from the walk but a literal FK beyond the tolerance (or NaN) is never a
    /// match, and says why.
    #[test]
    fn no_match_while_the_literal_fk_differs() {
        let tol = Tolerance::new(1e-4, 2e-4).unwrap();
        let bound = FkBound::new(tol, 1.5);
        assert!((bound.position - 4e-4).abs() < 1e-15);
        assert!(SheetCheck::new(vec![], literal(3.9e-4, 1.9e-4), bound).matches());
        let far = SheetCheck::new(vec![], literal(7.31, 3.137), bound);
        assert!(!far.matches());
        let named: Vec<Parameter> = far.differences().iter().map(|d| d.parameter).collect();
        assert_eq!(named, [Parameter::FkPosition, Parameter::FkOrientation]);
        let turned = SheetCheck::new(vec![], literal(5e-5, 3e-4), bound);
        assert!(!turned.matches());
        assert_eq!(turned.differences()[0].parameter, Parameter::FkOrientation);
        let nan = SheetCheck::new(vec![], literal(f64::NAN, 0.0), bound);
        assert!(!nan.matches());
        assert_eq!(nan.differences()[0].parameter, Parameter::FkPosition);
    }
}
