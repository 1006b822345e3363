//! Reading a written sheet back, in every output format, and proving what was written: the
//! `dh-workflows` library's [`dh_workflows::read_back`] and [`dh_workflows::prove`], under the CLI's old
//! paths.

pub use dh_workflows::prove::*;
pub use dh_workflows::read_back::read_back;
