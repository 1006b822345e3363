#![doc = include_str!("../README.md")]
//!
//! # Frames and units
//! Every line and pose a [`Chain`] returns is in its base link's frame; lengths in metres,
//! angles in radians. URDF `rpy` means `R = Rz(yaw) Ry(pitch) Rx(roll)`
//! ([`dh_core::pose::from_xyz_rpy`]).
//!
//! # What urdf-rs does and what is checked here
//! urdf-rs 0.10 validates almost nothing. It fills a missing `<origin>` with the identity, a
//! missing `<axis>` with `1 0 0` (the URDF default), and a missing `<limit>` with zeros (so a
//! revolute joint without limits is refused here as [`UrdfError::MissingLimit`]). It reads
//! `nan` and `inf`, drops vector tokens that are not numbers (`"1 x 2 3"` reads as `1 2 3`),
//! accepts any root element and ignores a second one, and its XML backend recurses once per
//! nesting level. Its backend rejects entity declarations as "malformed xml"; they are refused
//! here first with a clear [`UrdfError::EntityDeclaration`]. Positions are only in its XML
//! syntax errors; for the others the line is found in the source text.
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

mod chain;
mod error;
pub mod inertia;
mod locate;
mod model;
mod scan;

pub use chain::{Chain, MimicJoint};
pub use error::UrdfError;
pub use model::UrdfModel;
