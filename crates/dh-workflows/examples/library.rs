//! The library calls behind `urdf-dh extract`, `simulate` and `calibrate`, from Rust:
//! a URDF's DH table proved as written, a simulated measurement set with planted errors, and
//! its calibration with the calibrated model proved as written.
//!
//!     cargo run -p dh-workflows --example library     (from the repository root)

#![allow(clippy::print_stdout)] // an example prints what it shows

use dh_core::Convention;
use dh_workflows::calibration::{self, CalibrationRequest};
use dh_workflows::extract::{extract_bytes, prove_extracted, ExtractOptions};
use dh_workflows::simulation::{simulate, SimulationRequest};
use dh_workflows::Format;

fn main() -> anyhow::Result<()> {
    let mut warnings = Vec::new(); // `urdf-dh: warning:` lines, as the CLI prints them

    // Extraction: the Panda's table, written as YAML and proved by forward kinematics.
    let panda = "fixtures/robots/franka_panda/robot.urdf";
    let mut ex = extract_bytes(
        &std::fs::read(panda)?,
        "robot.urdf",
        None,
        None,
        &ExtractOptions::default(),
    )?;
    let (_yaml, passed) = prove_extracted(&mut ex, Format::Yaml, 1000, 1)?;
    println!(
        "{panda}: {} joints, proof passed: {passed}",
        ex.extraction.table.rows.len()
    );

    // Simulation: the UR5 sheet with 0.5 mm on a link length, 50 um noise.
    let ur5 = "fixtures/robots/ur5/vendor.yaml";
    let request = SimulationRequest {
        model: ur5.into(),
        base: None,
        tip: None,
        convention: Convention::Standard,
        poses: 150,
        noise: 5e-5,
        orientation_noise: None,
        cpa: false,
        arc: None,
        effects: vec![],
        inertials: None,
        gravity: None,
        errors: vec!["shoulder_lift_joint.a=0.0005".into()],
        random_errors: None,
        targets: 1,
        repeats: 1,
        validation: 0.2,
        sessions: 1,
        seed: 7,
    };
    let sim = simulate(&request, "ur5.csv", "ur5.truth.yaml", &mut warnings)?;
    let data = std::env::temp_dir().join("urdf-dh-example-ur5.csv");
    std::fs::write(&data, &sim.csv)?;

    // Calibration: the same run as `urdf-dh calibrate --model ur5 --data ur5.csv --out ...`.
    let mut request = CalibrationRequest::new(Some(ur5.into()), data.to_string_lossy());
    request.sigma = Some(5e-5);
    let mut calibrated = calibration::run(&request, &mut warnings)?;
    let out = std::env::temp_dir().join("urdf-dh-example-ur5-calibrated.yaml");
    let sheet = calibrated.model_file(&out.to_string_lossy(), Some(ur5), &mut warnings)?;
    if let calibration::Calibrated::Points(p) = &calibrated {
        let doc = &p.calibration.doc;
        let a = doc
            .parameters
            .iter()
            .find(|p| p.name == "shoulder_lift_joint.a");
        println!(
            "RMS {:.6} -> {:.6} m; shoulder_lift_joint.a {:+.6} m (planted +0.000500); model proved: {}",
            doc.rms_before,
            doc.rms_after,
            a.map_or(f64::NAN, |a| a.estimate - a.nominal),
            sheet.is_some() && calibrated.proved()
        );
    }
    std::fs::remove_file(&data)?;
    print!("{}", String::from_utf8_lossy(&warnings));
    Ok(())
}
