//! Reading input files (or standard input) with errors that name the file. The readers of text
//! and robot files (a URDF's chain, [`load_chain`], with its warnings, [`urdf_warnings`]) are
//! the `dh-workflows` library's ([`dh_workflows::input`]), re-exported here under their old paths.

pub use dh_workflows::input::{
    chain_error, display_name, load_chain, load_chain_bytes, read_bytes, read_data_bytes,
    read_data_text, read_robot, read_robot_bytes, read_text, urdf_warnings, utf8_text,
};
