//! End-to-end tests of the `urdf-dh` binary: exit code, stdout and stderr together.

mod batch;
mod bounds;
mod calibrate;
mod check;
mod check_cases;
mod check_round_trip;
mod common;
mod contacts;
mod corpus;
mod cpa;
mod default_tip;
mod diagnosis;
mod extract;
mod hostile_names;
mod import_columns;
mod invalid;
mod limits;
mod measured;
mod outputs;
mod pose6;
mod predict;
mod roundtrip;
mod sessions;
mod tree;
mod writers;
mod written;
