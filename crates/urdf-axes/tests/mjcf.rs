//! The MJCF reader on the project's own fixtures (`fixtures/mjcf`): every construct it takes,
//! against poses computed by MuJoCo 4.0.0 (`mj_kinematics`), and the bad inputs it refuses,
//! with messages naming the element and its line. The real models of `../shared/formats` are
//! checked against MuJoCo by `tests/formats/mjcf_oracle.py`.

use std::path::{Path, PathBuf};

use dh_core::pose::{from_xyz_rpy, to_xyz_rpy};
use dh_core::JointKind;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use urdf_axes::mjcf::{self, MjcfError};
use urdf_axes::{UrdfError, UrdfModel};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mjcf")
}

fn constructs() -> UrdfModel {
    let dir = fixtures();
    let text = std::fs::read_to_string(dir.join("constructs.xml")).unwrap();
    mjcf::read(&text, Some(&dir)).unwrap()
}

/// Reads `body` (the children of `<mujoco>`) without a folder.
fn read(body: &str) -> Result<UrdfModel, MjcfError> {
    mjcf::read(&format!("<mujoco model=\"t\">\n{body}\n</mujoco>"), None)
}

fn error(body: &str) -> String {
    read(body).unwrap_err().to_string()
}

/// Every MJCF chain of `../shared/formats/manifest.json` (the mujoco_menagerie arms) reads and
/// builds (their kinematics against MuJoCo's: `tests/formats/mjcf_oracle.py`). Skips, saying
/// so, without `../shared`.
#[test]
fn the_menagerie_chains_read() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/formats");
    let Ok(text) = std::fs::read_to_string(folder.join("manifest.json")) else {
        test_skips::skip("../shared/formats is absent");
        return;
    };
    let manifest: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut chains = 0;
    for e in manifest["models"].as_array().unwrap() {
        if e["format"] != "mjcf" {
            continue;
        }
        let path = folder.join(e["file"].as_str().unwrap());
        let bytes = std::fs::read(&path).unwrap();
        assert!(mjcf::is_mjcf(&bytes), "{}", path.display());
        let model = mjcf::from_bytes(&bytes, path.parent())
            .unwrap_or_else(|err| panic!("{}: {err}", path.display()));
        let chain = model
            .chain(e["base"].as_str(), e["tip"].as_str())
            .unwrap_or_else(|err| panic!("{}: {err}", e["id"]));
        assert!(
            chain.axes().len() >= 5,
            "{}: {} rows",
            e["id"],
            chain.axes().len()
        );
        let zero = vec![0.0; chain.axes().len()];
        assert!(chain.fk(&zero).translation.vector.relative_eq(
            &chain.tip_pose().translation.vector,
            1e-15,
            1e-15
        ));
        chains += 1;
    }
    assert_eq!(chains, 20);
}

#[test]
fn every_construct_gives_mujocos_pose() {
    let model = constructs();
    let chain = model.chain(Some("cart"), Some("hand")).unwrap();
    let rows: Vec<&str> = chain.axes().iter().map(|a| a.name.as_str()).collect();
    assert_eq!(rows, ["lift", "pan", "tilt", "elbow", "wrist"]);
    assert_eq!(
        chain.folded_fixed(),
        ["anchor:shoulder", "anchor:elbow", "weld:hand"]
    );
    // MuJoCo 4.0.0, qpos of lift, pan, tilt, elbow, wrist = 0.12, 0.3, -0.4, 1.1, 0.7 (the
    // others at qpos0): inv(pose(cart)) @ pose(hand) from data.xpos / data.xquat.
    let want = [
        [
            -0.8495825830829856,
            -0.5188311357633862,
            -0.09499308966717782,
            0.04016702381045412,
        ],
        [
            0.31074304661562674,
            -0.6378599125934098,
            0.7046797080137657,
            0.28641384567133327,
        ],
        [
            -0.4262020571302775,
            0.569165164489889,
            0.703137839992357,
            0.29442358402410335,
        ],
    ];
    let got = chain.fk(&[0.12, 0.3, -0.4, 1.1, 0.7]).to_homogeneous();
    for (i, row) in want.iter().enumerate() {
        for (j, &w) in row.iter().enumerate() {
            assert!((got[(i, j)] - w).abs() < 1e-12, "({i}, {j}): {got}");
        }
    }
}

#[test]
fn joints_take_their_class_limits_units_and_kind() {
    let model = constructs();
    let chain = model.chain(Some("cart"), Some("hand")).unwrap();
    let axes = chain.axes();
    let limits: Vec<Option<(f64, f64)>> = axes
        .iter()
        .map(|a| a.limits.map(|l| (l.lower, l.upper)))
        .collect();
    let deg = |x: f64| x.to_radians();
    assert_eq!(axes[0].kind, JointKind::Prismatic);
    assert_eq!(limits[0], Some((0.0, 0.4)), "slide range in metres");
    assert_eq!(
        limits[1],
        Some((deg(-90.0), deg(90.0))),
        "class 'arm' by childclass"
    );
    assert_eq!(limits[3], None, "class 'spin': limited=false");
    assert_eq!(
        limits[4],
        Some((deg(-170.0), deg(170.0))),
        "nested class 'wrist'"
    );
    // Two hinges in one body: a chain of zero-length links named after body and joint.
    assert!(model.links().contains(&"shoulder:pan"));
    assert!(model.joints().contains(&"weld:hand"));
    assert!(model.joints().contains(&"anchor:shoulder"));
}

#[test]
fn a_linear_joint_coupling_is_a_mimic_in_qpos() {
    let model = constructs();
    let chain = model.chain(Some("hand"), Some("finger_b")).unwrap();
    let m = &chain.mimics()[0];
    // qpos_b - ref_b = 0.005 + 1 (qpos_a - ref_a), ref_b = 0.01, ref_a = 0.
    assert_eq!(
        (m.joint.as_str(), m.driver.as_str()),
        ("finger_b", "finger_a")
    );
    assert_eq!(m.multiplier, 1.0);
    assert!((m.offset - 0.015).abs() < 1e-15, "{}", m.offset);
}

#[test]
fn default_tip_warnings_and_joints_without_one_axis() {
    let model = constructs();
    assert_eq!(model.root_link(), "world");
    assert_eq!(model.chain(Some("cart"), None).unwrap().tip(), "hand");
    let w = model.warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].element, "<connect>");
    assert_eq!(w[0].line, Some(51));
    let ball = model.chain(Some("cart"), Some("camera_mount")).unwrap_err();
    assert!(
        matches!(ball, UrdfError::JointTypeInChain { found: "ball", .. }),
        "{ball}"
    );
    assert!(
        ball.to_string().contains("joint 'gimbal' (line 30)"),
        "{ball}"
    );
    // One body on a free joint at the root: chains start below it by default.
    let default = model.chain(None, None).unwrap();
    assert_eq!((default.base(), default.tip()), ("cart", "hand"));
    let free = model
        .chain(Some("world"), Some("hand"))
        .unwrap_err()
        .to_string();
    assert!(
        free.contains("joint 'root'") && free.contains("found a free joint"),
        "{free}"
    );
}

#[test]
fn include_needs_a_folder_and_a_file() {
    let text = std::fs::read_to_string(fixtures().join("constructs.xml")).unwrap();
    let e = mjcf::read(&text, None).unwrap_err().to_string();
    assert_eq!(
        e,
        "<include> (line 42): cannot include 'forearm.xml': the model was not read from a file, so relative paths have no folder (give the mjcf as a file)"
    );
    let e = mjcf::read(
        "<mujoco>\n<worldbody>\n<include file=\"missing.xml\"/>\n</worldbody>\n</mujoco>",
        Some(&fixtures()),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("<include> (line 3): cannot read the included file 'missing.xml'"),
        "{e}"
    );
    let e = mjcf::read(
        "<mujoco>\n<include file=\"constructs.xml\"/>\n<include file=\"constructs.xml\"/>\n</mujoco>",
        Some(&fixtures()),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("included again") || e.contains("(forearm.xml"),
        "{e}"
    );
}

#[test]
fn bad_inputs_name_the_element_and_line() {
    let body =
        |inner: &str| format!("<worldbody>\n<body name=\"b\">\n{inner}\n</body>\n</worldbody>");
    let cases = [
        (
            body("<joint name=\"j\" class=\"nope\"/>"),
            "joint 'j' (line 4): attribute 'class': expected a default class, found 'nope', which no <default> defines",
        ),
        (
            "<worldbody>\n<body name=\"b\" quat=\"0 0 0 0\"/>\n</worldbody>".into(),
            "body 'b' (line 3): attribute 'quat': expected a quaternion of nonzero norm, found '0 0 0 0'",
        ),
        (
            body("<joint name=\"j\" axis=\"0 0 0\"/>"),
            "joint 'j' (line 4): attribute 'axis': expected a vector of nonzero length, found 0 0 0",
        ),
        (
            body("<joint name=\"j\" range=\"1 -1\"/>"),
            "joint 'j' (line 4): attribute 'range': expected lower < upper for a limited joint, found 1 -1",
        ),
        (
            body("<joint name=\"j\" type=\"screw\"/>"),
            "joint 'j' (line 4): attribute 'type': expected 'hinge', 'slide', 'ball' or 'free', found 'screw'",
        ),
        (
            body("<body name=\"c\"><freejoint name=\"f\"/></body>"),
            "freejoint 'f' (line 4): expected a free joint only as the one joint of a body whose parent is the world, found one in body 'c' (joint 1 of 1, parent 'b')",
        ),
        (
            body("<joint name=\"j\" pos=\"0 0\"/>"),
            "joint 'j' (line 4): attribute 'pos': expected 3 finite numbers, found '0 0'",
        ),
        (
            body("<body name=\"b\"/>"),
            "body 'b' (line 4): expected unique body names, found 'b' defined again (first on line 3)",
        ),
        (
            body("<attach model=\"m\" body=\"x\" prefix=\"p\"/>"),
            "<attach> (line 4): expected bodies written out, found <attach>, which urdf-dh does not expand (compile the model and save it with mj_saveLastXML)",
        ),
        (
            "<worldbody>\n<joint name=\"j\"/>\n</worldbody>".into(),
            "joint 'j' (line 3): expected joints inside a <body>, found one in the world body (it cannot move)",
        ),
        (
            "<compiler angle=\"grad\"/>".into(),
            "<compiler> (line 2): attribute 'angle': expected 'degree' or 'radian', found 'grad'",
        ),
        (
            body("<joint name=\"j\"/>") + "\n<equality>\n<joint joint1=\"j\" joint2=\"k\"/>\n</equality>",
            "<joint> (line 8): attribute 'joint2': expected a hinge or slide joint, found 'k'",
        ),
        (
            body("<joint name=\"j\" range=\"0 1\"/>").replace("<worldbody>", "<compiler autolimits=\"false\"/>\n<worldbody>"),
            "joint 'j' (line 5): expected attribute 'limited' for a joint with a 'range' when <compiler autolimits=\"false\">, found none",
        ),
    ];
    for (text, want) in cases {
        assert_eq!(error(&text), want, "{text}");
    }
    let e = mjcf::read("<robot name=\"r\"/>", None)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "mjcf parse error (line 1): expected a <mujoco> root element, found <robot>"
    );
    let e = mjcf::read("<mujoco>\n<worldbody>\n</mujoco>", None)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("mjcf parse error (line 3): "), "{e}");
}

#[test]
fn ref_is_folded_so_rows_take_qpos() {
    // A hinge with ref 90 deg about z at x = 1: at qpos = ref the body is where it is written.
    let m = read(
        "<worldbody>\n<body name=\"a\">\n<body name=\"b\" pos=\"1 0 0\">\n<joint name=\"h\" axis=\"0 0 1\" pos=\"0.5 0 0\" ref=\"90\"/>\n<body name=\"t\" pos=\"1 0 0\"/>\n</body>\n</body>\n</worldbody>\n<equality/>",
    )
    .unwrap();
    let chain = m.chain(Some("a"), Some("t")).unwrap();
    let at_ref = chain.fk(&[std::f64::consts::FRAC_PI_2]);
    assert!((at_ref.translation.vector - Vector3::new(2.0, 0.0, 0.0)).norm() < 1e-15);
    // At qpos = 0 the body has turned -90 deg about the anchor (1.5, 0, 0): t is at (1.5, -0.5, 0).
    let at_zero = chain.fk(&[0.0]);
    assert!(
        (at_zero.translation.vector - Vector3::new(1.5, -0.5, 0.0)).norm() < 1e-15,
        "{at_zero}"
    );
}

/// The reader stores rotations as URDF roll-pitch-yaw: exact enough only if the conversion is
/// exact everywhere, gimbal lock included.
#[test]
fn rotations_survive_rpy_at_gimbal_lock() {
    let mut worst: f64 = 0.0;
    let mut check = |q: UnitQuaternion<f64>| {
        let pose = Isometry3::from_parts(Vector3::new(0.1, 0.2, 0.3).into(), q);
        let (xyz, rpy) = to_xyz_rpy(&pose);
        let back = from_xyz_rpy(xyz, rpy);
        worst = worst.max(back.rotation.angle_to(&pose.rotation));
    };
    for k in 0..2000 {
        let t = k as f64 * 0.618_033_988_749_895;
        let axis = Vector3::new(t.sin(), (2.0 * t).cos(), (3.0 * t).sin() + 0.1);
        check(UnitQuaternion::from_scaled_axis(axis * (t % 3.1)));
        // Pitch of exactly and nearly +-pi/2, any roll and yaw.
        for pitch in [1.0, -1.0, 1.0 - 1e-9, -1.0 + 1e-12] {
            check(UnitQuaternion::from_euler_angles(
                t,
                pitch * std::f64::consts::FRAC_PI_2,
                2.0 * t,
            ));
        }
    }
    assert!(worst < 1e-15, "worst rotation lost: {worst:e} rad");
}

#[test]
fn mjcf_is_told_from_urdf_by_its_root() {
    assert!(mjcf::is_mjcf(
        b"<?xml version=\"1.0\"?>\n<!-- x -->\n<mujoco model=\"m\">"
    ));
    assert!(!mjcf::is_mjcf(
        b"<?xml version=\"1.0\"?>\n<robot name=\"mujoco\">"
    ));
}

mod props {
    use super::*;
    use proptest::prelude::*;

    /// One joint: hinge or slide, anchor, axis, ref.
    #[derive(Clone, Debug)]
    struct J {
        hinge: bool,
        pos: [f64; 3],
        axis: [f64; 3],
        reference: f64,
    }

    /// One body: pos, quat (w x y z, not normalized), joints.
    #[derive(Clone, Debug)]
    struct B {
        pos: [f64; 3],
        quat: [f64; 4],
        joints: Vec<J>,
    }

    fn v3(r: f64) -> impl Strategy<Value = [f64; 3]> {
        [-r..r, -r..r, -r..r]
    }

    fn joint() -> impl Strategy<Value = J> {
        (any::<bool>(), v3(0.3), v3(1.0), -3.0..3.0)
            .prop_filter("a nonzero axis", |(_, _, a, _)| {
                Vector3::from(*a).norm() > 0.1
            })
            .prop_map(|(hinge, pos, axis, reference)| J {
                hinge,
                pos,
                axis,
                reference,
            })
    }

    fn body() -> impl Strategy<Value = B> {
        (
            v3(0.5),
            [-1.0..1.0, -1.0..1.0, -1.0..1.0, -1.0..1.0],
            prop::collection::vec(joint(), 0..3),
        )
            .prop_filter("a quaternion of some length", |(_, q, _)| {
                q.iter().map(|x| x * x).sum::<f64>() > 0.01
            })
            .prop_map(|(pos, quat, joints)| B { pos, quat, joints })
    }

    fn text(bodies: &[B]) -> String {
        let mut s = String::from("<mujoco>\n<compiler angle=\"radian\"/>\n<worldbody>\n");
        let f = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        for (i, b) in bodies.iter().enumerate() {
            s += &format!(
                "<body name=\"b{i}\" pos=\"{}\" quat=\"{}\">\n",
                f(&b.pos),
                f(&b.quat)
            );
            for (k, j) in b.joints.iter().enumerate() {
                s += &format!(
                    "<joint name=\"j{i}_{k}\" type=\"{}\" pos=\"{}\" axis=\"{}\" ref=\"{:e}\"/>\n",
                    if j.hinge { "hinge" } else { "slide" },
                    f(&j.pos),
                    f(&j.axis),
                    j.reference
                );
            }
        }
        s += &"</body>\n".repeat(bodies.len());
        s + "</worldbody>\n</mujoco>\n"
    }

    /// MuJoCo's `mj_kinematics` for a serial chain, transcribed (engine_core_smooth.c): the
    /// body frame, then each joint on the right about its anchor in the moved frame.
    fn mujoco_fk(bodies: &[B], q: &mut impl Iterator<Item = f64>) -> Isometry3<f64> {
        let mut pos = Vector3::zeros();
        let mut rot = UnitQuaternion::identity();
        for b in bodies {
            let [w, x, y, z] = b.quat;
            let local = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, x, y, z));
            pos += rot * Vector3::from(b.pos);
            rot *= local;
            for j in &b.joints {
                let axis = nalgebra::Unit::new_normalize(Vector3::from(j.axis));
                let value = q.next().unwrap_or(0.0) - j.reference;
                let p = Vector3::from(j.pos);
                if j.hinge {
                    let anchor = pos + rot * p;
                    rot *= UnitQuaternion::from_axis_angle(&axis, value);
                    pos = anchor - rot * p;
                } else {
                    pos += rot * axis.into_inner() * value;
                }
            }
        }
        Isometry3::from_parts(pos.into(), rot)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn chains_move_as_mujoco_moves_them(
            bodies in prop::collection::vec(body(), 1..5),
            values in prop::collection::vec(-3.0..3.0f64, 12),
        ) {
            let n: usize = bodies.iter().map(|b| b.joints.len()).sum();
            prop_assume!(n > 0);
            let model = mjcf::read(&text(&bodies), None).unwrap();
            let tip = format!("b{}", bodies.len() - 1);
            let chain = model.chain(Some("world"), Some(&tip)).unwrap();
            let q = &values[..n];
            let got = chain.fk(q);
            let want = mujoco_fk(&bodies, &mut q.iter().copied());
            prop_assert!((got.translation.vector - want.translation.vector).norm() < 1e-12, "{got} {want}");
            prop_assert!(got.rotation.angle_to(&want.rotation) < 1e-12);
        }
    }
}

#[test]
fn what_cannot_change_the_chain_is_a_warning() {
    let m = read(
        "<worldbody>\n<body name=\"b\">\n<wibble/>\n<joint name=\"j\"/>\n<body name=\"c\">\n<joint name=\"k\"/>\n</body>\n</body>\n</worldbody>\n<foo/>\n<equality>\n<joint joint1=\"k\" joint2=\"j\" polycoef=\"0 1 0.5 0 0\"/>\n<joint joint1=\"k\" joint2=\"j\" active=\"false\"/>\n</equality>",
    )
    .unwrap();
    let w: Vec<String> = m.warnings().iter().map(ToString::to_string).collect();
    assert_eq!(
        w,
        [
            "<wibble> (line 4): unknown element <wibble> in body 'b'; ignored",
            "<foo> (line 11): unknown element <foo> in <mujoco>; ignored",
            "<joint> (line 13): a polynomial coupling beyond degree 1 is not a mimic; ignored",
            "<joint> (line 14): inactive (active=\"false\"); not taken as a mimic",
        ]
    );
    // Neither coupling is a mimic.
    assert!(m.chain(Some("b"), Some("c")).unwrap().mimics().is_empty());
}
