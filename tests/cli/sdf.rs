//! SDFormat input on the real files of `../shared/formats` (gazebo_models: PR2 1.4 and 1.5,
//! UR10, simple_arm, Robonaut, double pendulum): every chain of the manifest extracts and its
//! table verifies, and the models that also exist as URDF have the same forward kinematics as
//! that URDF. Needs ../shared; skips with a reason without it.

use nalgebra::Isometry3;
use urdf_axes::UrdfModel;

use crate::common::{run, skip_without_shared};

/// Every SDF chain of the manifest: `extract` exits 0 and its verification passes.
#[test]
fn every_manifest_sdf_chain_extracts_and_verifies() {
    let Some(shared) = skip_without_shared("sdf manifest") else {
        return;
    };
    let formats = shared.join("formats");
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(formats.join("manifest.json")).unwrap()).unwrap();
    let mut chains = 0;
    for m in manifest["models"].as_array().unwrap() {
        if m["format"] != "sdf" {
            continue;
        }
        let file = formats.join(m["file"].as_str().unwrap());
        let (base, tip) = (m["base"].as_str().unwrap(), m["tip"].as_str().unwrap());
        let out = run(
            &[
                "extract",
                file.to_str().unwrap(),
                "--base",
                base,
                "--tip",
                tip,
            ],
            None,
        );
        assert!(
            out.starts_with("exit: 0") && out.contains("PASS"),
            "{}: {out}",
            m["id"]
        );
        chains += 1;
    }
    assert_eq!(chains, 9, "expected the 9 SDF chains of the manifest");
    // The same chains through `batch`, one process: 9 tables proved.
    let list: String = manifest["models"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["format"] == "sdf")
        .map(|m| {
            format!(
                "{} {} {}\n",
                formats.join(m["file"].as_str().unwrap()).display(),
                m["base"].as_str().unwrap(),
                m["tip"].as_str().unwrap()
            )
        })
        .collect();
    let out = run(&["batch", "-"], Some(list.as_bytes()));
    assert!(
        out.starts_with("exit: 0")
            && out.contains("9 tables: 9 proved, 0 failed their proof, 0 refused"),
        "{out}"
    );
}

/// A deterministic joint vector in [-pi, pi) per sample.
fn samples(n_joints: usize, count: usize) -> Vec<Vec<f64>> {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..count)
        .map(|_| {
            (0..n_joints)
                .map(|_| {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1);
                    ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0 * std::f64::consts::PI
                })
                .collect()
        })
        .collect()
}

/// The oracle of the SDF reader: the same robot as a URDF (read by the URDF reader, which the
/// 278-chain corpus checks) has the same forward kinematics. The base links are the same
/// physical frame; the tip frames may differ by a constant (the UR10 SDF puts `wrist_3` on the
/// wrist centre, the URDF's `wrist_3_link` 0.0922 m out on the flange), fitted at q = 0:
/// `T_sdf(q) = T_urdf(q) · T_urdf(0)⁻¹ T_sdf(0)` at 200 joint vectors.
#[test]
fn sdf_models_have_the_forward_kinematics_of_their_urdf_siblings() {
    let Some(shared) = skip_without_shared("sdf oracle") else {
        return;
    };
    let sdf = shared.join("formats/sdf/gazebo_models");
    let cases = [
        (
            "pr2/model.sdf",
            "torso_lift_link",
            "r_wrist_roll_link",
            "robots-ext/willow_pr2/robot.urdf",
            "torso_lift_link",
            "r_wrist_roll_link",
            1e-12,
        ),
        (
            "pr2/model.sdf",
            "torso_lift_link",
            "l_wrist_roll_link",
            "robots-ext/willow_pr2/robot.urdf",
            "torso_lift_link",
            "l_wrist_roll_link",
            1e-12,
        ),
        (
            "pr2/model-1_4.sdf",
            "base_footprint",
            "r_wrist_roll_link",
            "robots-ext/willow_pr2/robot.urdf",
            "base_footprint",
            "r_wrist_roll_link",
            1e-12,
        ),
        // The UR10 SDF writes rounded numbers (1.57079, 3.58979e-09): 1e-8.
        (
            "ur10/ur10.sdf",
            "base",
            "wrist_3",
            "robots/ur10/robot.urdf",
            "base_link",
            "wrist_3_link",
            1e-8,
        ),
    ];
    for (file, base, tip, urdf, ubase, utip, tol) in cases {
        let s = UrdfModel::from_bytes(&std::fs::read(sdf.join(file)).unwrap()).unwrap();
        let u = UrdfModel::from_bytes(&std::fs::read(shared.join(urdf)).unwrap()).unwrap();
        let sc = s.chain(Some(base), Some(tip)).unwrap();
        let uc = u.chain(Some(ubase), Some(utip)).unwrap();
        let n = sc.axes().len();
        assert_eq!(n, uc.axes().len(), "{file}: joint count");
        let zero = vec![0.0; n];
        let tool: Isometry3<f64> = uc.fk(&zero).inverse() * sc.fk(&zero);
        let mut worst = (0.0f64, 0.0f64);
        for q in samples(n, 200) {
            let d = (uc.fk(&q) * tool).inverse() * sc.fk(&q);
            worst.0 = worst.0.max(d.translation.vector.norm());
            worst.1 = worst.1.max(d.rotation.angle());
        }
        println!(
            "{file} {base} -> {tip} vs {urdf}: {n} joints, max {:.1e} m {:.1e} rad",
            worst.0, worst.1
        );
        assert!(
            worst.0 <= tol && worst.1 <= tol,
            "{file} -> {tip}: {worst:?}"
        );
    }
}
