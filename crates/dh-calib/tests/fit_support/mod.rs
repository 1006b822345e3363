//! Robots and helpers shared by the `fit_*` tests.
#![allow(dead_code)]

use std::f64::consts::{FRAC_PI_2, PI};

use dh_core::{Convention, DhRow, DhTable, Limits};
use nalgebra::Isometry3;

fn limited(mut row: DhRow, lower_deg: f64, upper_deg: f64) -> DhRow {
    row.limits = Some(Limits {
        lower: lower_deg.to_radians(),
        upper: upper_deg.to_radians(),
    });
    row
}

/// Universal Robots UR5 (CB3), vendor DH; joints 2, 3, 4 are parallel.
pub fn ur5() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            limited(
                DhRow::revolute("j1", 0.0, FRAC_PI_2, 0.089159, 0.0),
                -180.0,
                180.0,
            ),
            limited(DhRow::revolute("j2", -0.425, 0.0, 0.0, 0.0), -180.0, 180.0),
            limited(
                DhRow::revolute("j3", -0.39225, 0.0, 0.0, 0.0),
                -180.0,
                180.0,
            ),
            limited(
                DhRow::revolute("j4", 0.0, FRAC_PI_2, 0.10915, 0.0),
                -180.0,
                180.0,
            ),
            limited(
                DhRow::revolute("j5", 0.0, -FRAC_PI_2, 0.09465, 0.0),
                -180.0,
                180.0,
            ),
            limited(DhRow::revolute("j6", 0.0, 0.0, 0.0823, 0.0), -180.0, 180.0),
        ],
    }
}

/// A large industrial 6R in the KUKA KR 120-class layout (lengths 0.35 to 1.2 m), standard DH.
pub fn kr_like() -> DhTable {
    DhTable {
        convention: Convention::Standard,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        rows: vec![
            limited(
                DhRow::revolute("a1", 0.35, -FRAC_PI_2, 0.675, 0.0),
                -185.0,
                185.0,
            ),
            limited(
                DhRow::revolute("a2", 1.15, 0.0, 0.0, -FRAC_PI_2),
                -140.0,
                -5.0,
            ),
            limited(
                DhRow::revolute("a3", 0.041, FRAC_PI_2, 0.0, 0.0),
                -120.0,
                155.0,
            ),
            limited(
                DhRow::revolute("a4", 0.0, -FRAC_PI_2, -1.2, 0.0),
                -350.0,
                350.0,
            ),
            limited(
                DhRow::revolute("a5", 0.0, FRAC_PI_2, 0.0, 0.0),
                -125.0,
                125.0,
            ),
            limited(DhRow::revolute("a6", 0.0, PI, -0.215, 0.0), -350.0, 350.0),
        ],
    }
}
