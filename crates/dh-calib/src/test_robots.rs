//! Robots the unit tests share.

use std::f64::consts::FRAC_PI_2;

use dh_core::{Convention, DhRow, DhTable};
use nalgebra::Isometry3;

/// A UR5 in the vendor's standard DH (metres, radians), joints `j1` to `j6`, base and tool at
/// the identity.
pub(crate) fn ur5() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            DhRow::revolute("j1", 0.0, FRAC_PI_2, 0.089159, 0.0),
            DhRow::revolute("j2", -0.425, 0.0, 0.0, 0.0),
            DhRow::revolute("j3", -0.39225, 0.0, 0.0, 0.0),
            DhRow::revolute("j4", 0.0, FRAC_PI_2, 0.10915, 0.0),
            DhRow::revolute("j5", 0.0, -FRAC_PI_2, 0.09465, 0.0),
            DhRow::revolute("j6", 0.0, 0.0, 0.0823, 0.0),
        ],
    }
}
