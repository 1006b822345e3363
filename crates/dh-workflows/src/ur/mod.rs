//! A Universal Robots controller's factory calibration: the nominal DH tables of the UR
//! family as Universal Robots publishes them ([`nominal`]), the controller's
//! `calibration.conf` ([`CalibrationConf`]), and the calibrated table they make
//! ([`calibrated`]): every row's standard DH `theta`, `a`, `d`, `alpha` plus the controller's
//! `delta_theta`, `delta_a`, `delta_d`, `delta_alpha` (metres, radians).
//!
//! # Frames
//! Standard DH, `A_i(q) = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`: the controller's own
//! model (its deltas are in that form). On arms whose joints 2, 3, 4 are parallel by design,
//! the calibrated axes are a milliradian off parallel and their common normals lie metres away
//! along them: a real UR3's `delta_d` are -6.29 m, +8.57 m and -2.28 m, which cancel along the
//! run (FK is right; the DH frames are far from the arm). [`crate::urdf_writer`] places a
//! URDF's link frames back on the arm (each slides along its own joint axis).

mod conf;
mod nominal;

pub use conf::{CalibrationConf, Deltas};
pub use nominal::{nominal, NominalSheet, NOMINAL};

use anyhow::Result;
use dh_core::pose::{rot_x, rot_z, trans_x, trans_z};
use dh_core::{Convention, DhTable};
use nalgebra::Isometry3;

/// The calibrated table: `nominal`'s rows plus `deltas` (row by row, in row order).
///
/// # Errors
/// A nominal table that is not in the standard convention, or whose row count differs from
/// the deltas' (naming both counts).
pub fn calibrated(nominal: &DhTable, deltas: &Deltas) -> Result<DhTable> {
    if nominal.convention != Convention::Standard {
        anyhow::bail!(
            "expected a nominal table in the standard convention (the controller's deltas are standard DH), found {}",
            nominal.convention
        );
    }
    if nominal.rows.len() != deltas.len() {
        anyhow::bail!(
            "expected deltas for the nominal table's {} joints, found {}",
            nominal.rows.len(),
            deltas.len()
        );
    }
    let mut table = nominal.clone();
    for (k, row) in table.rows.iter_mut().enumerate() {
        let [dt, da, dd, dal] = deltas.row(k);
        row.theta += dt;
        row.a += da;
        row.d += dd;
        row.alpha += dal;
    }
    Ok(table)
}

/// The calibrated arm's forward kinematics computed from the nominal numbers and the deltas
/// directly (`base · Π Rz(q+θ+δθ) Tz(d+δd) Tx(a+δa) Rx(α+δα) · tool`), without a [`DhTable`]:
/// the oracle a written calibrated sheet or URDF is compared with.
pub fn calibrated_fk(nominal: &DhTable, deltas: &Deltas, q: &[f64]) -> Isometry3<f64> {
    let mut pose = nominal.base;
    for (k, (row, qk)) in nominal.rows.iter().zip(q).enumerate() {
        let [dt, da, dd, dal] = deltas.row(k);
        pose = pose
            * rot_z(qk + row.theta + dt)
            * trans_z(row.d + dd)
            * trans_x(row.a + da)
            * rot_x(row.alpha + dal);
    }
    pose * nominal.tool
}

#[cfg(test)]
mod tests;
