#![doc = include_str!("../README.md")]
//!
//! # Frames and units
//! Every line and pose a [`Chain`] returns is in its base link's frame; lengths in metres,
//! angles in radians. URDF `rpy` means `R = Rz(yaw) Ry(pitch) Rx(roll)`
//! ([`dh_core::pose::from_xyz_rpy`]).
//!
//! # Reading
//! One linear scan of the text ([`UrdfModel::parse`]), without recursion and without entity
//! expansion, then the model is read from it: strict on what defines the tree and on the
//! joints of the chosen chain, lenient (a [`Warning`] with the element and its line) on what
//! cannot change the chain's kinematics, as ROS's urdfdom is (it ignores unknown elements,
//! takes the first `<material>`, logs a malformed `rgba` and goes on). Inputs beyond
//! [`MAX_URDF_BYTES`] are refused.
//!
//! # SDFormat
//! A document whose root element is `<sdf>` is read by the SDFormat reader (`sdf` module: poses
//! and frames by the document's version, 1.4 to 1.11) into the same robot model, so chains,
//! checks and warnings work on it unchanged; see [`UrdfModel::parse`].
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
mod check;
mod error;
pub mod inertia;
mod mimic;
pub mod mjcf;
mod model;
mod read;
mod robot;
mod scan;
mod sdf;
mod text;
mod tip;

pub use chain::{Chain, MimicJoint};
pub use error::UrdfError;
pub use model::{UrdfModel, MAX_URDF_BYTES};
pub use robot::{Warning, MAX_WARNINGS};
