//! Reading a written sheet back, in every output format, and proving what was written: the
//! `dh-sheet` library's [`dh_sheet::read_back`] and [`dh_sheet::prove`], under the CLI's old
//! paths.

pub use dh_sheet::prove::*;
pub use dh_sheet::read_back::read_back;
