//! End-to-end tests of the `urdf-dh` binary: exit code, stdout and stderr together.

mod calibrate;
mod check;
mod common;
mod contacts;
mod corpus;
mod cpa;
mod extract;
mod invalid;
mod measured;
mod tree;
mod written;
