//! The published measurement sets in `../shared/measured` (outside the repository), each fitted
//! nominal -> geometric -> selected effects with the project's fixture models
//! (`fixtures/measured/<set>/`), printed as the Markdown of `docs/results.md`.
//!
//! ```sh
//! cargo run --release -p dh-calib --example real_sets            # every set
//! cargo run --release -p dh-calib --example real_sets -- boby    # one set
//! ```
//!
//! A set whose files are absent is skipped with a message on stderr. The fixture readers here
//! are deliberately small and serial (the CLI owns the full sheet format). The DLR Agile Justin
//! set is a kinematic tree: its tree sheet is read by the library (`dh_workflows::tree_sheet`),
//! and it runs there (`-- dlr` prints the commands; see docs/results.md).
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use dh_calib::calibrate::{CalibrationOptions, Report};
use dh_calib::cpa::{analyse, CpaOptions};
use dh_calib::data::{Measurements, Split};
use dh_calib::diagnose::{diagnose_tree, DiagnoseOptions, EffectSelection};
use dh_calib::effects::{parse_label_in, EffectContext};
use dh_calib::findings::CandidateStatus;
use dh_calib::gravity::{GravityModel, Inertial, Inertials};
use dh_calib::import::{import, Layout, Source};
use dh_calib::model::{Effect, Model, ModelOptions};
use dh_calib::tree::DhTree;
use dh_core::pose::from_xyz_rpy;
use dh_core::{Convention, DhRow, DhTable, JointKind, Limits};
use nalgebra::{Isometry3, Point3, Vector3};
use serde_yaml::Value;

mod loading;
mod report;
mod sets;
use loading::*;
use report::*;
use sets::*;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let sets: [(&str, Run); 5] = [
        ("innopolis", innopolis),
        ("boby", boby),
        ("dlr", dlr),
        ("liaowu", liaowu),
        ("mukca", mukca),
    ];
    for (name, run) in sets {
        if !args.is_empty() && !args.iter().any(|a| a == name) {
            continue;
        }
        if let Err(e) = run() {
            eprintln!("{name}: skipped: {e}");
        }
    }
}
