//! Hand-computed SDFormat fixtures, one per rule: each pose below is worked out on paper from
//! the spec's rules and compared with the chain the reader builds (axis lines in the base
//! link's frame, tip poses).

use std::f64::consts::FRAC_PI_2;

use approx::assert_relative_eq;
use nalgebra::{Isometry3, Vector3};

use crate::{UrdfError, UrdfModel};

/// Exact arithmetic on these small poses: a few ulps.
const EXACT: f64 = 1e-12;

fn sdf(version: &str, body: &str) -> String {
    format!("<?xml version='1.0'?>\n<sdf version='{version}'>\n<model name='m'>\n{body}</model>\n</sdf>\n")
}

/// Asserts that joint `k` of the chain has its axis through `point` along `direction`.
fn assert_axis(
    model: &UrdfModel,
    base: &str,
    tip: &str,
    k: usize,
    point: [f64; 3],
    direction: [f64; 3],
) {
    let chain = model.chain(Some(base), Some(tip)).expect("chain");
    let line = &chain.axes().get(k).expect("joint").line;
    assert_relative_eq!(line.direction(), Vector3::from(direction), epsilon = EXACT);
    assert!(
        line.distance_to_point(&Vector3::from(point)) < EXACT,
        "joint {k}: axis misses {point:?} by {}",
        line.distance_to_point(&Vector3::from(point))
    );
}

const TWO_LINKS_ROTATED_CHILD: &str = "<link name='a'/>
<link name='b'><pose>1 0 0 0 0 1.5707963267948966</pose></link>
<joint name='j' type='revolute'><parent>a</parent><child>b</child>
  <axis><xyz>1 0 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>\n";

/// The joint frame is the child link's: `b` is turned 90 degrees about z, so the axis `1 0 0`
/// is the world's y from 1.5 on (through b's origin, (1, 0, 0)); in 1.4 it is expressed in the
/// model frame: x.
#[test]
fn the_axis_is_in_the_joint_frame_from_1_5_and_in_the_model_frame_in_1_4() {
    for (version, direction) in [
        ("1.4", [1.0, 0.0, 0.0]),
        ("1.5", [0.0, 1.0, 0.0]),
        ("1.7", [0.0, 1.0, 0.0]),
        ("1.9", [0.0, 1.0, 0.0]),
    ] {
        let m = UrdfModel::parse(&sdf(version, TWO_LINKS_ROTATED_CHILD)).expect(version);
        assert_axis(&m, "a", "b", 0, [1.0, 0.0, 0.0], direction);
        let chain = m.chain(Some("a"), Some("b")).expect("chain");
        let limits = chain.axes().first().and_then(|a| a.limits).expect("limits");
        assert_eq!((limits.lower, limits.upper), (-1.0, 1.0));
    }
}

/// `use_parent_model_frame` (1.5, 1.6) and `expressed_in='__model__'` (1.7+) both put the axis
/// in the model frame: x.
#[test]
fn use_parent_model_frame_and_expressed_in_put_the_axis_in_the_model_frame() {
    let legacy = TWO_LINKS_ROTATED_CHILD.replace(
        "<xyz>1 0 0</xyz>",
        "<xyz>1 0 0</xyz><use_parent_model_frame>true</use_parent_model_frame>",
    );
    let modern = TWO_LINKS_ROTATED_CHILD.replace(
        "<xyz>1 0 0</xyz>",
        "<xyz expressed_in='__model__'>1 0 0</xyz>",
    );
    for text in [
        sdf("1.5", &legacy),
        sdf("1.6", &legacy),
        sdf("1.8", &modern),
    ] {
        let m = UrdfModel::parse(&text).expect("sdf");
        assert_axis(&m, "a", "b", 0, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    }
    // expressed_in another link: `a`'s frame is the model's here, so x again; an unknown name
    // is refused on the chain.
    let other =
        TWO_LINKS_ROTATED_CHILD.replace("<xyz>1 0 0</xyz>", "<xyz expressed_in='a'>1 0 0</xyz>");
    assert_axis(
        &UrdfModel::parse(&sdf("1.7", &other)).expect("sdf"),
        "a",
        "b",
        0,
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
    );
    let unknown = TWO_LINKS_ROTATED_CHILD.replace(
        "<xyz>1 0 0</xyz>",
        "<xyz expressed_in='nowhere'>1 0 0</xyz>",
    );
    let e = UrdfModel::parse(&sdf("1.7", &unknown))
        .expect("sdf")
        .chain(Some("a"), Some("b"))
        .expect_err("unknown frame");
    assert!(e.to_string().contains("'nowhere'"), "{e}");
}

/// The joint's pose is relative to the child link: `b` at (1, 0, 0) turned 90 degrees about x,
/// joint pose `0 0 0.5`: the joint origin is b + Rx(90)(0, 0, 0.5) = (1, -0.5, 0), its axis
/// `0 0 1` the world's -y. The tip (b's frame) stays where b is.
#[test]
fn the_joint_pose_is_relative_to_the_child_link_and_the_tip_stays_on_the_link() {
    let body = "<link name='a'/>
<link name='b'><pose>1 0 0 1.5707963267948966 0 0</pose></link>
<joint name='j' type='continuous'><pose>0 0 0.5 0 0 0</pose><parent>a</parent><child>b</child>
  <axis><xyz>0 0 1</xyz></axis></joint>\n";
    for version in ["1.4", "1.6", "1.7"] {
        let m = UrdfModel::parse(&sdf(version, body)).expect(version);
        // 1.4 expresses the axis in the model frame: z stays the world's z, through (1, -0.5, 0).
        let direction = if version == "1.4" {
            [0.0, 0.0, 1.0]
        } else {
            [0.0, -1.0, 0.0]
        };
        assert_axis(&m, "a", "b", 0, [1.0, -0.5, 0.0], direction);
        let chain = m.chain(Some("a"), Some("b")).expect("chain");
        let expected = Isometry3::new(
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(FRAC_PI_2, 0.0, 0.0),
        );
        assert_relative_eq!(chain.tip_pose(), expected, epsilon = EXACT);
        // Turning the joint by pi turns b's origin about the joint axis through (1, -0.5, 0):
        // along -y (1.6, 1.7) it lies on the axis and stays; about z (1.4) it goes to (1, -1, 0).
        let turned = chain.fk(&[std::f64::consts::PI]).translation.vector;
        let expected = if version == "1.4" {
            [1.0, -1.0, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        assert_relative_eq!(turned, Vector3::from(expected), epsilon = EXACT);
    }
}

/// 1.7 `relative_to` chains and `<frame>`: F is attached to a, 1 m above it; b is placed
/// relative to F (1 m along F's x, F turned 90 degrees about z, so along the world's y); the
/// joint's frame is given relative to F too, 1 m above F: the axis `1 0 0` in that frame (turned
/// like F) is the world's y, through (0, 0, 2).
#[test]
fn relative_to_chains_and_frames_resolve_to_hand_computed_poses() {
    let body = "<link name='a'/>
<frame name='F' attached_to='a'><pose>0 0 1 0 0 1.5707963267948966</pose></frame>
<frame name='G'><pose relative_to='F'>0 0 1 0 0 0</pose></frame>
<link name='b'><pose relative_to='F'>1 0 0 0 0 0</pose></link>
<joint name='j' type='revolute'><pose relative_to='G'/><parent>a</parent><child>b</child>
  <axis><xyz>1 0 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.7", body)).expect("sdf");
    assert_axis(&m, "a", "b", 0, [0.0, 0.0, 2.0], [0.0, 1.0, 0.0]);
    let chain = m.chain(Some("a"), Some("b")).expect("chain");
    assert_relative_eq!(
        chain.tip_pose().translation.vector,
        Vector3::new(0.0, 1.0, 1.0),
        epsilon = EXACT
    );
    // The joint frame is off b's frame: an added link and fixed joint carry it.
    assert!(m.links().contains(&"j#frame"));
    assert_eq!(chain.joints(), ["j", "j#child"]);
    // A joint's child may be a frame (1.8): its link is the frame's, its default pose the frame's.
    let to_frame = "<link name='a'/><link name='b'><pose>1 0 0 0 0 0</pose></link>
<frame name='H' attached_to='b'><pose>0 0 1 0 0 0</pose></frame>
<joint name='j' type='continuous'><parent>a</parent><child>H</child><axis><xyz>0 1 0</xyz></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.8", to_frame)).expect("sdf");
    assert_axis(&m, "a", "b", 0, [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]);
}

/// Before 1.7 `//pose/@frame` and `<frame>` had no meaning: ignored with a warning naming the
/// line.
#[test]
fn pose_frames_before_1_7_are_warned_and_ignored() {
    let body = "<link name='a'/>\n<link name='b'><pose frame='a'>1 0 0 0 0 0</pose></link>
<frame name='F'/>
<joint name='j' type='continuous'><parent>a</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.5", body)).expect("sdf");
    assert_axis(&m, "a", "b", 0, [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    let w = m.warnings();
    assert!(
        w.iter()
            .any(|w| w.line == Some(5) && w.element == "link 'b'" && w.message.contains("frame")),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|w| w.line == Some(6) && w.message.contains("<frame>")),
        "{w:?}"
    );
}

/// A nested model's links are named with its scope and placed in its frame: `arm` at
/// (0, 0, 1) turned 90 degrees about z, its link `l1` 1 m along arm's x: (0, 1, 1); a joint of
/// the outer model names `arm::l1`, a joint of the nested model its own `l1`, `l2`.
#[test]
fn nested_models_scope_names_and_compose_poses() {
    let body = "<link name='base'/>
<model name='arm'><pose>0 0 1 0 0 1.5707963267948966</pose>
  <link name='l1'><pose>1 0 0 0 0 0</pose></link>
  <link name='l2'><pose>2 0 0 0 0 0</pose></link>
  <joint name='j2' type='revolute'><parent>l1</parent><child>l2</child>
    <axis><xyz>0 0 1</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>
</model>
<joint name='j1' type='revolute'><parent>base</parent><child>arm::l1</child>
  <axis><xyz>1 0 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>\n";
    for version in ["1.6", "1.8"] {
        let m = UrdfModel::parse(&sdf(version, body)).expect(version);
        assert!(m.links().contains(&"arm::l2"), "{:?}", m.links());
        // j1's axis: x of l1's frame (turned like arm), the world's y, through (0, 1, 1).
        assert_axis(&m, "base", "arm::l2", 0, [0.0, 1.0, 1.0], [0.0, 1.0, 0.0]);
        // j2's axis: z through l2 at (0, 2, 1).
        assert_axis(&m, "base", "arm::l2", 1, [0.0, 2.0, 1.0], [0.0, 0.0, 1.0]);
        let chain = m.chain(Some("base"), Some("arm::l2")).expect("chain");
        assert_eq!(chain.joints(), ["j1", "arm::j2"]);
    }
}

/// A world of several models: every name takes its model's scope, the models hang from `world`
/// by floating joints (a chain refuses to cross them), and a chain inside one model works.
#[test]
fn a_world_of_models_scopes_names_and_refuses_chains_across_models() {
    let model = |name: &str, x: f64| {
        format!("<model name='{name}'><pose>{x} 0 0 0 0 0</pose><link name='base'/><link name='tip'><pose>0 0 1 0 0 0</pose></link>
<joint name='j' type='prismatic'><parent>base</parent><child>tip</child><axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>1</upper></limit></axis></joint></model>\n")
    };
    let text = format!(
        "<sdf version='1.9'><world name='w'>\n{}{}</world></sdf>",
        model("left", 1.0),
        model("right", -1.0)
    );
    let m = UrdfModel::parse(&text).expect("world");
    assert_eq!(m.root_link(), "world");
    for l in ["left::base", "left::tip", "right::base", "right::tip"] {
        assert!(m.links().contains(&l), "{l}: {:?}", m.links());
    }
    let chain = m
        .chain(Some("left::base"), Some("left::tip"))
        .expect("chain");
    assert_eq!(chain.joints(), ["left::j"]);
    assert_relative_eq!(
        chain.fk(&[0.25]).translation.vector,
        Vector3::new(0.0, 0.0, 1.25),
        epsilon = EXACT
    );
    let e = m
        .chain(Some("world"), Some("right::tip"))
        .expect_err("floating");
    assert!(
        matches!(
            e,
            UrdfError::JointTypeInChain {
                found: "floating",
                ..
            }
        ),
        "{e}"
    );
    // A joint to `world` is a joint from the world link, at the model's pose.
    let fixed = text.replace(
        "<joint name='j' type='prismatic'>",
        "<joint name='fix' type='fixed'><parent>world</parent><child>base</child></joint><joint name='j' type='prismatic'>",
    );
    let m = UrdfModel::parse(&fixed).expect("world");
    let chain = m.chain(Some("world"), Some("right::tip")).expect("chain");
    assert_relative_eq!(
        chain.fk(&[0.0]).translation.vector,
        Vector3::new(-1.0, 0.0, 1.0),
        epsilon = EXACT
    );
}

/// Ball, universal and other joints are refused on a chain with the type named, and warned
/// elsewhere; so is a second parent of a link (a loop), which is left out of the tree.
#[test]
fn joints_without_one_axis_are_refused_on_the_chain_and_loops_are_cut() {
    let body = "<link name='a'/><link name='b'/><link name='c'/>
<joint name='hinge' type='revolute'><parent>a</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>
<joint name='ball' type='ball'><parent>b</parent><child>c</child></joint>
<joint name='loop' type='revolute'><parent>c</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.7", body)).expect("sdf");
    let e = m.chain(Some("a"), Some("c")).expect_err("ball on chain");
    assert_eq!(
        e.to_string(),
        "joint 'ball' (line 6): expected an sdformat joint of type revolute, continuous, prismatic or fixed, found 'ball'"
    );
    let chain = m.chain(Some("a"), Some("b")).expect("chain");
    let w = m.warnings_for(&chain);
    assert!(w.iter().any(|w| w.element == "joint 'ball'"), "{w:?}");
    assert!(m
        .warnings()
        .iter()
        .any(|w| w.element == "joint 'loop'" && w.line == Some(7) && w.message.contains("loop")));
}

/// What defines the frames is strict: an unknown `relative_to`, a cycle, a repeated name, a
/// malformed pose are errors naming the line.
#[test]
fn unresolvable_frames_are_errors_naming_the_line() {
    let cases = [
        ("<link name='a'/>\n<link name='b'><pose relative_to='x'>0 0 0 0 0 0</pose></link>\n", "found 'x'", 5),
        ("<frame name='f'><pose relative_to='g'/></frame>\n<frame name='g'><pose relative_to='f'/></frame>\n<link name='a'/>\n", "cycle", 4),
        ("<link name='a'/>\n<link name='a'/>\n", "defined again", 5),
        ("<link name='a'>\n<pose>0 0 0 0 0</pose></link>\n", "expected 6 numbers", 5),
    ];
    for (body, what, line) in cases {
        let e = UrdfModel::parse(&sdf("1.7", body)).expect_err(what);
        let text = e.to_string();
        assert!(
            text.contains(what) && text.contains(&format!("(line {line})")),
            "{what}: {text}"
        );
    }
    assert!(matches!(
        UrdfModel::parse("<sdf version='1.7'/>"),
        Err(UrdfError::Sdf { .. })
    ));
    assert!(matches!(
        UrdfModel::parse("<!DOCTYPE sdf [<!ENTITY a 'b'>]><sdf version='1.7'/>"),
        Err(UrdfError::EntityDeclaration { .. })
    ));
    let empty =
        UrdfModel::parse("<sdf version='1.6'>\n<model name='arm'/></sdf>").expect_err("no link");
    assert_eq!(
        empty.to_string(),
        "sdformat error (line 2): <model> 'arm': expected at least one <link>, found none"
    );
}

/// A joint whose child no element defines is named as written, in every version: before 1.7
/// its frame has a private key (a joint may share a link's name), which a message never shows.
#[test]
fn a_joint_with_an_unknown_child_is_named_as_written() {
    let body = "<link name='a'/>\n<joint name='j' type='revolute'><parent>a</parent><child>nope</child><axis><xyz>0 0 1</xyz></axis></joint>\n";
    for version in ["1.6", "1.7"] {
        let e = UrdfModel::parse(&sdf(version, body)).expect_err(version);
        let text = e.to_string();
        assert!(
            text.contains("joint 'j': expected its <child> to name a link or frame of its model, found 'nope'"),
            "{version}: {text}"
        );
        assert!(!text.contains('\u{0}'), "{version}: {text:?}");
    }
    let cycle = "<frame name='f'><pose relative_to='g'/></frame>\n<frame name='g'><pose relative_to='f'/></frame>\n<link name='a'/>\n";
    let e = UrdfModel::parse(&sdf("1.7", cycle)).expect_err("cycle");
    assert!(
        e.to_string()
            .contains("frame 'f': expected poses that lead to the world frame"),
        "{e}"
    );
}

/// SDFormat before 1.7 gave links and joints names of their own (gazebo_models' UR10 has a link
/// and a joint `wrist_1`); from 1.7 one scope holds both.
#[test]
fn legacy_links_and_joints_may_share_a_name() {
    let body = "<link name='a'/><link name='b'/>
<joint name='b' type='revolute'><parent>a</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.5", body)).expect("1.5");
    assert_eq!(
        m.chain(Some("a"), Some("b")).expect("chain").joints(),
        ["b"]
    );
    assert!(UrdfModel::parse(&sdf("1.7", body)).is_err());
}

/// The format is told by the root element, whatever comes before it.
#[test]
fn the_root_element_tells_the_format() {
    use super::root_element_name;
    assert_eq!(
        root_element_name("<?xml version='1.0'?>\n<!-- c -->\n<!DOCTYPE x>\n<sdf version='1.9'>"),
        Some("sdf")
    );
    assert_eq!(
        root_element_name("\u{feff}<robot name='r'/>"),
        Some("robot")
    );
    assert_eq!(root_element_name("<!-- unclosed"), None);
    assert_eq!(root_element_name(""), None);
}

/// A loop's closing joint is found from the root, whatever the document order: written first,
/// the loop joint `c -> b` still leaves `a -> b` as b's parent.
#[test]
fn the_tree_is_grown_from_the_root_so_a_loop_written_first_is_still_cut() {
    let body = "<link name='a'/><link name='b'><pose>1 0 0 0 0 0</pose></link><link name='c'><pose>2 0 0 0 0 0</pose></link>
<joint name='loop' type='revolute'><parent>c</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>
<joint name='hinge' type='continuous'><parent>a</parent><child>b</child><axis><xyz>0 0 1</xyz></axis></joint>
<joint name='elbow' type='continuous'><parent>b</parent><child>c</child><axis><xyz>0 0 1</xyz></axis></joint>\n";
    let m = UrdfModel::parse(&sdf("1.7", body)).expect("sdf");
    let chain = m.chain(Some("a"), Some("c")).expect("chain");
    assert_eq!(chain.joints(), ["hinge", "elbow"]);
    assert!(m
        .warnings()
        .iter()
        .any(|w| w.element == "joint 'loop'" && w.line == Some(5)));
}
