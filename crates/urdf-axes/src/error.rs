use thiserror::Error;

mod wording;
pub(crate) use wording::list;
use wording::{at, counted, cycle, first, joint_cycle, suggest};

/// Everything that can be wrong with a URDF or with the chain asked of it.
///
/// Messages are lowercase, say "expected X, found Y", and name the joint or link and, when it is
/// known, the 1-based line of the source text where that joint or link (or the offending child
/// element) starts.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum UrdfError {
    /// The bytes are not UTF-8.
    #[error("expected utf-8 text, found an invalid byte at offset {offset} (line {line})")]
    NotUtf8 {
        /// Byte offset of the first invalid byte.
        offset: usize,
        /// 1-based line of that byte.
        line: usize,
    },
    /// The document is larger than [`crate::MAX_URDF_BYTES`] (refused before reading it all).
    #[error(
        "expected a robot description of at most {limit} bytes, found {}",
        .size.map_or_else(|| "more".to_owned(), |s| format!("{s} bytes"))
    )]
    TooLarge {
        /// Bytes found, when known (reading from a pipe stops after the limit).
        size: Option<usize>,
        /// The limit.
        limit: usize,
    },
    /// The document declares entities. Refused before parsing: nested entity expansion (the
    /// "billion laughs" document) can exhaust memory, and no URDF needs entities.
    #[error(
        "entity declaration (line {line}): expected a urdf without <!ENTITY declarations, \
         found one (refused: entity expansion can exhaust memory)"
    )]
    EntityDeclaration {
        /// 1-based line of the `<!ENTITY`.
        line: usize,
    },
    /// Not XML, truncated XML, an empty document, a root element other than `<robot>`, a
    /// missing required attribute or element, or a malformed number.
    #[error("urdf parse error{}: {message}", at(.line))]
    Parse {
        /// What was expected and what was found.
        message: String,
        /// 1-based line, when it could be found.
        line: Option<usize>,
    },
    /// The robot has no `<link>`.
    #[error("robot '{robot}': expected at least one <link>, found none")]
    NoLinks {
        /// Robot name.
        robot: String,
    },
    /// Two links share a name.
    #[error(
        "link '{link}'{}: expected unique link names, found '{link}' defined again{}",
        at(.line),
        first(.first_line)
    )]
    DuplicateLink {
        /// The repeated name.
        link: String,
        /// Line of the second definition.
        line: Option<usize>,
        /// Line of the first definition.
        first_line: Option<usize>,
    },
    /// A link or joint name holds a control character (C0, DEL or C1): it would corrupt every
    /// table, CSV and terminal line the name is written to, and YAML cannot carry some of them
    /// unescaped; or a bidirectional formatting character (U+202E...), which makes the name
    /// display as something it is not.
    #[error(
        "{kind} '{name}'{}: expected a name without control or bidirectional formatting characters, found {code} at character {position}",
        at(.line)
    )]
    ControlCharacterInName {
        /// `link` or `joint`.
        kind: &'static str,
        /// The name, as Rust debug text (control characters escaped).
        name: String,
        /// The character, as `U+XXXX`.
        code: String,
        /// Its position in the name (1-based, in characters).
        position: usize,
        /// Line of the element.
        line: Option<usize>,
    },
    /// Two joints share a name.
    #[error(
        "joint '{joint}'{}: expected unique joint names, found '{joint}' defined again{}",
        at(.line),
        first(.first_line)
    )]
    DuplicateJoint {
        /// The repeated name.
        joint: String,
        /// Line of the second definition.
        line: Option<usize>,
        /// Line of the first definition.
        first_line: Option<usize>,
    },
    /// A joint names a parent or child link that the URDF does not define.
    #[error(
        "joint '{joint}'{}: expected an existing {role} link, found '{link}', which no <link> defines",
        at(.line)
    )]
    MissingLink {
        /// The joint.
        joint: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The undefined link name.
        link: String,
        /// Line of the joint (or of its `<parent>`/`<child>` element).
        line: Option<usize>,
    },
    /// A link is the child of two joints.
    #[error(
        "link '{link}': expected one parent joint, found two: '{first}' and '{second}'{}",
        at(.line)
    )]
    TwoParents {
        /// The link.
        link: String,
        /// The first joint naming it as child.
        first: String,
        /// The second joint naming it as child.
        second: String,
        /// Line of the second joint.
        line: Option<usize>,
    },
    /// The joints form a cycle (the URDF still has a root elsewhere).
    #[error(
        "joint '{joint}'{}: expected a tree of links, found a cycle {}",
        at(.line),
        cycle(.links)
    )]
    Cycle {
        /// The links of the cycle, each the parent of the next, the first repeated at the end.
        links: Vec<String>,
        /// A joint of the cycle.
        joint: String,
        /// Line of that joint.
        line: Option<usize>,
    },
    /// Every link is some joint's child, so there is no root (the joints form a cycle).
    #[error(
        "expected one root link (a link that is no joint's child), found none: the joints form a cycle {}",
        cycle(.links)
    )]
    NoRoot {
        /// The links of a cycle, as in [`UrdfError::Cycle`].
        links: Vec<String>,
    },
    /// More than one link has no parent joint: the URDF is not one tree.
    #[error(
        "expected one root link (a link that is no joint's child), found {}: {}",
        .roots.len(),
        list(.roots)
    )]
    SeveralRoots {
        /// The parentless links, in document order.
        roots: Vec<String>,
    },
    /// A NaN or infinite number in an origin, axis, limit or mimic.
    #[error("joint '{joint}'{}: {what}: expected a finite number, found {value}", at(.line))]
    NonFinite {
        /// The joint.
        joint: String,
        /// Which number: `origin xyz`, `origin rpy`, `axis xyz`, `limit lower`, ...
        what: &'static str,
        /// The value.
        value: f64,
        /// Line of the element holding it.
        line: Option<usize>,
    },
    /// A finite origin coordinate, limit or mimic number beyond ±1e9 (metres or radians): no
    /// robot's, and its table in millimetres or degrees would overflow.
    #[error(
        "joint '{joint}'{}: {what}: expected a magnitude of at most 1e9, found {value:e}",
        at(.line)
    )]
    OutOfRange {
        /// The joint.
        joint: String,
        /// Which number, as in [`UrdfError::NonFinite`].
        what: &'static str,
        /// The value.
        value: f64,
        /// Line of the element holding it.
        line: Option<usize>,
    },
    /// A moving joint's axis has zero length.
    #[error(
        "joint '{joint}'{}: axis xyz: expected a non-zero direction, found {} {} {}",
        at(.line),
        .axis[0],
        .axis[1],
        .axis[2]
    )]
    ZeroAxis {
        /// The joint.
        joint: String,
        /// The axis as written.
        axis: [f64; 3],
        /// Line of the `<axis>` element.
        line: Option<usize>,
    },
    /// A joint's lower limit is above its upper limit.
    #[error(
        "joint '{joint}'{}: limit: expected lower <= upper, found lower {lower} > upper {upper}",
        at(.line)
    )]
    LimitsReversed {
        /// The joint.
        joint: String,
        /// Lower limit (radians or metres).
        lower: f64,
        /// Upper limit (radians or metres).
        upper: f64,
        /// Line of the `<limit>` element.
        line: Option<usize>,
    },
    /// A revolute or prismatic joint without `<limit>` (URDF requires one; only continuous
    /// joints are unlimited).
    #[error(
        "joint '{joint}'{}: expected a <limit> element (required for {kind} joints; use type \
         continuous for an unlimited revolute joint), found none",
        at(.line)
    )]
    MissingLimit {
        /// The joint.
        joint: String,
        /// `revolute` or `prismatic`.
        kind: &'static str,
        /// Line of the joint.
        line: Option<usize>,
    },
    /// A joint type that is not URDF (`spherical`, `ball`, or any other word).
    #[error(
        "joint '{joint}'{}: expected type revolute, continuous, prismatic, fixed, floating or \
         planar, found '{found}'",
        at(.line)
    )]
    UnsupportedJointType {
        /// The joint.
        joint: String,
        /// The type as written.
        found: String,
        /// Line of the joint.
        line: Option<usize>,
    },
    /// An SDFormat document whose frames, poses or joints cannot be resolved (an unknown
    /// `relative_to`, a cycle of frames, a malformed `<pose>`), or that is not `<sdf>` with a
    /// `<model>` or `<world>`.
    #[error("sdformat error{}: {message}", at(.line))]
    Sdf {
        /// What was expected and what was found, naming the element.
        message: String,
        /// 1-based line, when it could be found.
        line: Option<usize>,
    },
    /// An SDFormat joint of a type with no single axis (`ball`, `universal`, `revolute2`,
    /// `screw`, `gearbox`): refused on a chain, a warning elsewhere.
    #[error(
        "joint '{joint}'{}: expected an sdformat joint of type revolute, continuous, prismatic \
         or fixed, found '{found}'",
        at(.line)
    )]
    SdfJointType {
        /// The joint (scoped, `model::joint`, when the file has several models).
        joint: String,
        /// The type as written.
        found: String,
        /// Line of the joint.
        line: Option<usize>,
    },
    /// A `<mimic>` names a joint the URDF does not define.
    #[error(
        "joint '{joint}'{}: mimic: expected an existing driver joint, found '{driver}', which no <joint> defines",
        at(.line)
    )]
    UnknownMimicJoint {
        /// The mimicking joint.
        joint: String,
        /// The undefined driver name.
        driver: String,
        /// Line of the `<mimic>` element.
        line: Option<usize>,
    },
    /// A `<mimic>` that names its own joint (found by fuzzing: extract wrote it, and the sheet
    /// reader refuses it).
    #[error(
        "joint '{joint}'{}: mimic: expected another joint to follow, found itself",
        at(.line)
    )]
    MimicItself {
        /// The joint.
        joint: String,
        /// Line of the `<mimic>` element.
        line: Option<usize>,
    },
    /// Joints that mimic each other in a cycle (each follows the next, the last the first):
    /// no joint of the cycle has a value of its own.
    #[error(
        "joint '{}'{}: mimic: expected drivers that end at a joint that mimics none, found a cycle {}",
        .joints.first().map_or("", String::as_str),
        at(.line),
        joint_cycle(.joints, *.length)
    )]
    MimicCycle {
        /// The joints of the cycle from this one, each mimicking the next, the first repeated
        /// at the end; of a cycle longer than 8 joints only the first 6 and the last 2 (so that
        /// every joint of a long cycle does not hold all of it).
        joints: Vec<String>,
        /// Joints in the cycle.
        length: usize,
        /// Line of the first joint's `<mimic>`.
        line: Option<usize>,
    },
    /// A chain of mimics (each joint following the next) whose composed map from the joint
    /// that mimics none, `q = m · q_root + o`, has `|m|` or `|o|` beyond 1e9 (or overflows):
    /// each link may be within range and the product still not (1e9 per link over 40 links
    /// is beyond any float), so the joint's value over the root's range is not a number.
    #[error(
        "joint '{joint}'{}: mimic: expected its chain of drivers to '{root}' to compose to a multiplier and offset of magnitude at most 1e9, found {what} {value:e}",
        at(.line)
    )]
    MimicChainOutOfRange {
        /// The mimicking joint.
        joint: String,
        /// The joint at the end of its drivers, which mimics none.
        root: String,
        /// `multiplier` or `offset`.
        what: &'static str,
        /// The composed value (may be infinite).
        value: f64,
        /// Line of the joint's `<mimic>`.
        line: Option<usize>,
    },
    /// A `<mimic>` whose driver is not a revolute, continuous or prismatic joint.
    #[error(
        "joint '{joint}'{}: mimic: expected a revolute, continuous or prismatic driver, found \
         '{driver}', a {kind} joint",
        at(.line)
    )]
    MimicOfFixed {
        /// The mimicking joint.
        joint: String,
        /// The driver.
        driver: String,
        /// The driver's type (`fixed`, `floating`, `planar`).
        kind: &'static str,
        /// Line of the `<mimic>` element.
        line: Option<usize>,
    },
    /// A base or tip link name that the URDF does not define.
    #[error(
        "{role} link '{link}': expected a link of the urdf, found no such link{}",
        suggest(.candidates)
    )]
    UnknownLink {
        /// `base` or `tip`.
        role: &'static str,
        /// The name asked for.
        link: String,
        /// Close names (or every link, when there are few; with many links and none close,
        /// the leaves for a tip and the root for a base).
        candidates: Vec<String>,
    },
    /// No tip was given and several leaves below the base end equally long runs of moving
    /// joints (two arms of one length, a humanoid), or none does.
    #[error(
        "expected one tip below '{base}' at the end of the longest run of moving joints, found \
         {}: {} (choose one as the tip)",
        .leaves.len(),
        counted(.leaves, .moving)
    )]
    SeveralLeaves {
        /// The base link.
        base: String,
        /// The candidate tips, in document order.
        leaves: Vec<String>,
        /// Per candidate: the moving joints from the base down to it.
        moving: Vec<usize>,
    },
    /// The tip is not below the base.
    #[error(
        "tip link '{tip}' is not below base link '{base}': expected a chain of joints from \
         '{base}' down to '{tip}', found none{}",
        if *.reversed { " (the base is below the tip: swap them)" } else { "" }
    )]
    Disconnected {
        /// The base link.
        base: String,
        /// The tip link.
        tip: String,
        /// The base is below the tip (the two were given the wrong way round).
        reversed: bool,
    },
    /// A floating or planar joint between base and tip: neither has one axis line.
    #[error(
        "joint '{joint}'{}: on the chain from '{base}' to '{tip}', expected a revolute, \
         continuous, prismatic or fixed joint, found a {found} joint",
        at(.line)
    )]
    JointTypeInChain {
        /// The joint.
        joint: String,
        /// `floating` or `planar`.
        found: &'static str,
        /// Chain base link.
        base: String,
        /// Chain tip link.
        tip: String,
        /// Line of the joint.
        line: Option<usize>,
    },
    /// Base and tip are joined only by fixed joints (or are the same link).
    #[error(
        "chain from '{base}' to '{tip}': expected at least one revolute, continuous or prismatic \
         joint, found none"
    )]
    NoMovingJoint {
        /// The base link.
        base: String,
        /// The tip link.
        tip: String,
    },
    /// Joint values given to [`crate::Chain::try_fk`] or [`crate::Chain::axis_lines`] do not match
    /// the chain's moving joints.
    #[error("expected {expected} joint values (one per moving joint), found {found}")]
    JointCount {
        /// Moving joints of the chain.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// Finite inputs whose composition overflowed (for example two origins of 1e308 m).
    #[error("joint '{joint}': {cause}")]
    Geometry {
        /// The joint (or the tip link) where it happened.
        joint: String,
        /// What dh-core refused.
        cause: dh_core::CoreError,
    },
}

impl UrdfError {
    /// Whether the error is about the choice of base and tip (an unknown or ambiguous link,
    /// a tip not below the base, a floating or planar joint or no moving joint between them)
    /// rather than about the file.
    pub fn is_choice(&self) -> bool {
        matches!(
            self,
            UrdfError::UnknownLink { .. }
                | UrdfError::SeveralLeaves { .. }
                | UrdfError::Disconnected { .. }
                | UrdfError::JointTypeInChain { .. }
                | UrdfError::NoMovingJoint { .. }
                | UrdfError::JointCount { .. }
                | UrdfError::Geometry { .. }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_appear_only_when_known() {
        let e = UrdfError::ZeroAxis {
            joint: "j".into(),
            axis: [0.0; 3],
            line: Some(7),
        };
        assert_eq!(
            e.to_string(),
            "joint 'j' (line 7): axis xyz: expected a non-zero direction, found 0 0 0"
        );
        let e = UrdfError::Parse {
            message: "expected x, found y".into(),
            line: None,
        };
        assert_eq!(e.to_string(), "urdf parse error: expected x, found y");
    }

    #[test]
    fn long_lists_and_cycles_are_cut() {
        let names: Vec<String> = (0..10_000).map(|i| format!("l{i}")).collect();
        let e = UrdfError::SeveralLeaves {
            base: "b".into(),
            leaves: names.clone(),
            moving: vec![1; names.len()],
        };
        assert_eq!(
            e.to_string(),
            "expected one tip below 'b' at the end of the longest run of moving joints, found \
             10000: 'l0' (1 moving joint), 'l1' (1 moving joint), 'l2' (1 moving joint), \
             'l3' (1 moving joint), 'l4' (1 moving joint), 'l5' (1 moving joint), \
             'l6' (1 moving joint), 'l7' (1 moving joint) and 9992 more (choose one as the tip)"
        );
        let mut links = names;
        links.push("l0".into());
        let e = UrdfError::NoRoot { links };
        assert!(
            e.to_string().ends_with(
                "cycle l0 -> l1 -> l2 -> l3 -> l4 -> l5 -> ... -> l9999 -> l0 (10000 links)"
            ),
            "{e}"
        );
        let short: Vec<String> = ["a", "b", "a"].map(String::from).to_vec();
        assert!(UrdfError::NoRoot { links: short }
            .to_string()
            .ends_with("cycle a -> b -> a"));
    }
}
