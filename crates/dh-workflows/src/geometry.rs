//! The geometry a face names: the `dh-core` library's types, re-exported here so that the
//! faces (the command line, the Python package, the web page) depend on this one layer.
//!
//! A DH table ([`DhTable`], rows [`DhRow`] of a [`JointKind`]) in either [`Convention`]; the
//! [`Tolerance`] every discrete decision takes (metres and radians); a joint axis as a Plücker
//! [`Line`]; an extraction's facts ([`Extraction`]) and a proof's [`Bound`]. Frames and units
//! are `dh_core`'s: metres and radians, a table's `base` is DH frame 0 in the base link frame
//! and its `tool` the tip link frame in the last DH frame.

pub use dh_core::pose::from_xyz_rpy;
pub use dh_core::{Bound, Convention, DhRow, DhTable, Extraction, JointKind, Line, Tolerance};
