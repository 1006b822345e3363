//! MJCF bodies and joints as the crate's robot model ([`crate::robot::Robot`]): every body a
//! link (the world body is the link `world`), every hinge and slide joint a URDF joint whose
//! value is MuJoCo's `qpos`, so that chains, default tips, mimics and the forward kinematics
//! oracle work as for a URDF.
//!
//! The frames (how MuJoCo's `mj_kinematics` becomes URDF joints, `ref` folded in, anchors
//! undone by the next origin or `anchor:BODY`) are described in [`super`]'s docs.

use std::collections::HashMap;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use super::defaults::Classes;
use super::error::MjcfError;
use super::orient::{self, attr_numbers, boolean, numbers, Compiler};
use super::xml::Node;
use crate::robot::{Inertial, Joint, JointType, Link, MimicSpec, Origin, Robot};

/// The name of the world body.
pub(crate) const WORLD: &str = "world";

/// Elements of a body (or frame) that cannot change the kinematic tree: skipped silently.
const INERT: [&str; 8] = [
    "inertial",
    "geom",
    "site",
    "camera",
    "light",
    "plugin",
    "composite",
    "flexcomp",
];

/// A moving joint's facts needed by `<equality>`: its index in the model and its `ref`.
struct JointFacts {
    index: usize,
    reference: f64,
    scalar: bool,
}

/// A body, joint or frame found inside a body: the element, the pose of its enclosing frames in
/// the body frame, and the innermost `childclass` around it.
type Placed<'n> = (&'n Node, Isometry3<f64>, Option<&'n str>);

/// A joint read: the URDF joint (parent, child and origin still to fill in), its frame in the
/// (moved) body frame, and the anchor `p` whose `T(-p)` follows it (`None` when there is none
/// to undo: a slide or free joint, or an anchor at the body origin).
struct Parsed {
    joint: Joint,
    frame: Isometry3<f64>,
    after: Option<Vector3<f64>>,
}

/// Builds the [`Robot`] of a document.
pub(crate) struct Builder<'c> {
    classes: &'c Classes,
    compiler: Compiler,
    pub robot: Robot,
    bodies: HashMap<String, usize>,
    joints: HashMap<String, JointFacts>,
    /// Bodies on a free joint (children of the world).
    pub free_bodies: Vec<String>,
}

impl<'c> Builder<'c> {
    pub fn new(classes: &'c Classes, compiler: Compiler, name: String) -> Self {
        Builder {
            classes,
            compiler,
            robot: Robot {
                name,
                ..Robot::default()
            },
            bodies: HashMap::new(),
            joints: HashMap::new(),
            free_bodies: Vec::new(),
        }
    }

    /// Warns about element `e`.
    pub fn warn(&mut self, e: &Node, message: String) {
        let element = match &e.file {
            Some(f) => format!("{} in {f}", e.describe()),
            None => e.describe(),
        };
        self.robot.warn(element, e.line, message);
    }

    /// The world link and everything below the `<worldbody>` elements.
    pub fn world(&mut self, worldbodies: &[&Node], line: usize) -> Result<(), MjcfError> {
        self.robot.links.push(Link {
            name: WORLD.to_owned(),
            line,
            inertial: Ok(None),
        });
        self.bodies.insert(WORLD.to_owned(), line);
        for wb in worldbodies {
            let (mut joints, mut bodies) = (Vec::new(), Vec::new());
            self.collect(wb, Isometry3::identity(), None, &mut joints, &mut bodies)?;
            if let Some((j, _, _)) = joints.first() {
                return Err(j.error(
                    "expected joints inside a <body>, found one in the world body (it cannot move)",
                ));
            }
            for (b, frame, cc) in bodies {
                self.body(b, WORLD, frame, cc)?;
            }
        }
        Ok(())
    }

    /// Sorts the children of a body, the world body or a frame into joints and bodies, going
    /// into frames.
    fn collect<'n>(
        &mut self,
        container: &'n Node,
        frame: Isometry3<f64>,
        childclass: Option<&'n str>,
        joints: &mut Vec<Placed<'n>>,
        bodies: &mut Vec<Placed<'n>>,
    ) -> Result<(), MjcfError> {
        for c in &container.children {
            match c.name.as_str() {
                "joint" | "freejoint" => joints.push((c, frame, childclass)),
                "body" => bodies.push((c, frame, childclass)),
                "frame" => {
                    let f = frame * orient::pose(c, &self.compiler)?;
                    let cc = self.childclass(c)?.or(childclass);
                    self.collect(c, f, cc, joints, bodies)?;
                }
                "attach" | "replicate" => {
                    return Err(c.error(format!(
                        "expected bodies written out, found <{}>, which urdf-dh does not expand (compile the model and save it with mj_saveLastXML)",
                        c.name
                    )))
                }
                name if INERT.contains(&name) => {}
                other => {
                    let message = format!("unknown element <{other}> in {}; ignored", container.describe());
                    self.warn(c, message);
                }
            }
        }
        Ok(())
    }

    /// The `childclass` of a body or frame, checked to exist.
    fn childclass<'n>(&self, e: &'n Node) -> Result<Option<&'n str>, MjcfError> {
        match e.attr("childclass") {
            Some(c) if !self.classes.has(c) => Err(e.error(format!(
                "attribute 'childclass': expected a default class, found '{c}', which no <default> defines"
            ))),
            other => Ok(other),
        }
    }

    /// A name for `e`: its `name`, or one made of its tag and line.
    fn name_of(e: &Node) -> String {
        match (e.attr("name"), &e.file) {
            (Some(n), _) => n.to_owned(),
            (None, Some(f)) => format!("({} {f}:{})", e.name, e.line),
            (None, None) => format!("({} line {})", e.name, e.line),
        }
    }

    /// Body `b`, child of link `parent`, inside frames whose pose in the parent's frame is
    /// `placed`.
    fn body(
        &mut self,
        b: &Node,
        parent: &str,
        placed: Isometry3<f64>,
        inherited: Option<&str>,
    ) -> Result<(), MjcfError> {
        let name = Self::name_of(b);
        if let Some(first) = self.bodies.insert(name.clone(), b.line) {
            return Err(b.error(format!(
                "expected unique body names, found '{name}' defined again (first on line {first})"
            )));
        }
        let pose = placed * orient::pose(b, &self.compiler)?;
        let childclass = self.childclass(b)?.or(inherited);
        let (mut joints, mut bodies) = (Vec::new(), Vec::new());
        self.collect(
            b,
            Isometry3::identity(),
            childclass,
            &mut joints,
            &mut bodies,
        )?;
        let inertial = self.inertial(b);
        self.robot.links.push(Link {
            name: name.clone(),
            line: b.line,
            inertial,
        });
        let mut prev = parent.to_owned();
        let mut pending = pose;
        let count = joints.len();
        for (k, &(j, frame, cc)) in joints.iter().enumerate() {
            let Parsed {
                mut joint,
                frame: joint_frame,
                after,
            } = self.joint(j, frame, cc, &name, parent, k, count)?;
            joint.origin = Origin::of(&(pending * joint_frame));
            let last = k + 1 == count;
            let child = if last && after.is_none() {
                name.clone()
            } else {
                let link = format!("{name}:{}", joint.name);
                self.robot.links.push(Link {
                    name: link.clone(),
                    line: j.line,
                    inertial: Ok(None),
                });
                link
            };
            joint.parent = std::mem::replace(&mut prev, child.clone());
            joint.child = child;
            pending = after.map_or_else(Isometry3::identity, |p| {
                Isometry3::from_parts(Translation3::from(-p), UnitQuaternion::identity())
            });
            self.robot.joints.push(joint);
        }
        if count == 0 || prev != name {
            let prefix = if count == 0 { "weld" } else { "anchor" };
            self.robot.joints.push(Joint::fixed(
                format!("{prefix}:{name}"),
                b.line,
                prev,
                name.clone(),
                b.line,
                Origin::of(&pending),
            ));
        }
        for (child, frame, cc) in bodies {
            self.body(child, &name, frame, cc)?;
        }
        Ok(())
    }

    /// `<inertial pos mass>` of a body: the centre of mass in the body frame.
    fn inertial(&mut self, b: &Node) -> Result<Option<Inertial>, String> {
        let Some(i) = b.children.iter().find(|c| c.name == "inertial") else {
            return Ok(None);
        };
        let read = || -> Result<Inertial, MjcfError> {
            let com = attr_numbers::<3>(i, "pos")?.unwrap_or_default();
            let mass = match i.attr("mass") {
                Some(m) => numbers::<1>(i, "mass", m)?[0],
                None => return Err(i.error("expected attribute 'mass', found none")),
            };
            Ok(Inertial { mass, com })
        };
        read().map(Some).map_err(|e| {
            let m = match e {
                MjcfError::Invalid { message, .. } => message,
                other => other.to_string(),
            };
            self.warn(i, format!("{m}; the inertial is ignored"));
            m
        })
    }

    /// One `<joint>` or `<freejoint>` of body `body` (child of `parent`), the `k`-th of `count`:
    /// the URDF joint, its frame and its anchor ([`Parsed`]).
    #[allow(clippy::too_many_arguments)]
    fn joint(
        &mut self,
        j: &Node,
        frame: Isometry3<f64>,
        childclass: Option<&str>,
        body: &str,
        parent: &str,
        k: usize,
        count: usize,
    ) -> Result<Parsed, MjcfError> {
        let classes = self.classes;
        let class = if j.name == "freejoint" {
            super::defaults::MAIN
        } else {
            classes.class_of(j, childclass)?
        };
        let get = |attr: &str| {
            if j.name == "freejoint" {
                j.attr(attr)
            } else {
                classes.attr(j, "joint", class, attr)
            }
        };
        let kind = if j.name == "freejoint" {
            "free"
        } else {
            get("type").unwrap_or("hinge")
        };
        let name = Self::name_of(j);
        let num3 = |attr: &str, default: [f64; 3]| -> Result<[f64; 3], MjcfError> {
            get(attr).map_or(Ok(default), |v| numbers::<3>(j, attr, v))
        };
        let pos = frame * Point3::from(num3("pos", [0.0; 3])?);
        let axis = frame.rotation * Vector3::from(num3("axis", [0.0, 0.0, 1.0])?);
        let reference = match get("ref") {
            Some(v) => numbers::<1>(j, "ref", v)?[0],
            None => 0.0,
        };
        let mut joint = Joint::fixed(
            name.clone(),
            j.line,
            String::new(),
            String::new(),
            j.line,
            Origin::default(),
        );
        let anchor = (pos.coords != Vector3::zeros()).then_some(pos.coords);
        let (kind, reference, after) = match kind {
            "hinge" | "slide" => {
                let unit = orient::unit(j, "axis", axis.into())?;
                joint.axis = unit.into_inner().into();
                let hinge = kind == "hinge";
                let reference = if hinge {
                    self.compiler.radians(reference)
                } else {
                    reference
                };
                joint.limit = self.limit(j, &get, hinge)?;
                let kind = match (hinge, joint.limit.is_some()) {
                    (true, true) => JointType::Revolute,
                    (true, false) => JointType::Continuous,
                    (false, _) => JointType::Prismatic,
                };
                (kind, reference, if hinge { anchor } else { None })
            }
            "ball" => (JointType::Ball, 0.0, anchor),
            "free" => {
                if parent != WORLD || count > 1 {
                    return Err(j.error(format!(
                        "expected a free joint only as the one joint of a body whose parent is the world, found one in body '{body}' (joint {} of {count}, parent '{parent}')",
                        k + 1
                    )));
                }
                self.free_bodies.push(body.to_owned());
                (JointType::Free, 0.0, None)
            }
            other => {
                return Err(j.error(format!(
                    "attribute 'type': expected 'hinge', 'slide', 'ball' or 'free', found '{other}'"
                )))
            }
        };
        joint.kind = Some(kind);
        let facts = JointFacts {
            // The caller pushes the joint next.
            index: self.robot.joints.len(),
            reference,
            scalar: kind.is_moving(),
        };
        if self.joints.insert(name.clone(), facts).is_some() {
            return Err(j.error(format!(
                "expected unique joint names, found '{name}' defined again"
            )));
        }
        // The joint frame in the (moved) body frame, with `ref` folded in: hinge
        // `T(p) R(a, -ref)`, slide `T(-ref a)`, ball `T(p)`, free the body frame.
        let unit_axis = Vector3::from(joint.axis);
        let frame = match kind {
            JointType::Prismatic => Isometry3::from_parts(
                Translation3::from(-reference * unit_axis),
                UnitQuaternion::identity(),
            ),
            _ => Isometry3::from_parts(
                Translation3::from(anchor.unwrap_or_default()),
                UnitQuaternion::from_scaled_axis(unit_axis * -reference),
            ),
        };
        Ok(Parsed {
            joint,
            frame,
            after,
        })
    }

    /// The joint's limits (radians or metres), `None` when it is not limited: `limited` true or
    /// false, or `auto` (the default), limited when `autolimits` is on and `range` is set
    /// (MuJoCo's `checklimited`).
    fn limit<'a>(
        &self,
        j: &Node,
        get: &dyn Fn(&str) -> Option<&'a str>,
        hinge: bool,
    ) -> Result<Option<(f64, f64)>, MjcfError> {
        let range = get("range")
            .map(|v| numbers::<2>(j, "range", v))
            .transpose()?
            .unwrap_or([0.0, 0.0]);
        let has_range = range != [0.0, 0.0];
        let limited = match get("limited").unwrap_or("auto") {
            "auto" if self.compiler.autolimits => has_range,
            "auto" if has_range => {
                return Err(j.error(
                    "expected attribute 'limited' for a joint with a 'range' when <compiler autolimits=\"false\">, found none",
                ))
            }
            "auto" => false,
            other => boolean(j, "limited", other)?,
        };
        if !limited {
            return Ok(None);
        }
        let [lower, upper] = range.map(|r| if hinge { self.compiler.radians(r) } else { r });
        if lower >= upper {
            return Err(j.error(format!(
                "attribute 'range': expected lower < upper for a limited joint, found {} {}",
                range[0], range[1]
            )));
        }
        Ok(Some((lower, upper)))
    }

    /// `<equality>`: a `<joint>` coupling `joint1 = polycoef(joint2)` with a linear polynomial
    /// becomes a mimic of `joint2`; other constraints are warned about and ignored.
    pub fn equality(&mut self, eq: &Node) -> Result<(), MjcfError> {
        for e in &eq.children {
            if e.name != "joint" {
                let message = format!(
                    "a <{}> constraint closes a loop or couples bodies, which a serial chain cannot hold; ignored",
                    e.name
                );
                self.warn(e, message);
                continue;
            }
            let classes = self.classes;
            let class = classes.class_of(e, None)?;
            let get = |attr: &str| classes.attr(e, "equality", class, attr);
            let active = get("active").map_or(Ok(true), |v| boolean(e, "active", v))?;
            let coef = get("polycoef")
                .map(|v| numbers::<5>(e, "polycoef", v))
                .transpose()?
                .unwrap_or([0.0, 1.0, 0.0, 0.0, 0.0]);
            let Some(j1) = e.attr("joint1") else {
                return Err(e.error("expected attribute 'joint1', found none"));
            };
            let facts = |name: &str, attr: &str| {
                self.joints
                    .get(name)
                    .filter(|f| f.scalar)
                    .map(|f| (f.index, f.reference))
                    .ok_or_else(|| {
                        e.error(format!(
                            "attribute '{attr}': expected a hinge or slide joint, found '{name}'"
                        ))
                    })
            };
            let (follower, r1) = facts(j1, "joint1")?;
            let Some(j2) = e.attr("joint2") else {
                self.warn(
                    e,
                    format!("locks joint '{j1}' to a constant, which a table cannot hold; ignored"),
                );
                continue;
            };
            let (_, r2) = facts(j2, "joint2")?;
            if !active {
                self.warn(
                    e,
                    "inactive (active=\"false\"); not taken as a mimic".into(),
                );
                continue;
            }
            if coef.get(2..).is_some_and(|c| c.iter().any(|&x| x != 0.0)) {
                self.warn(
                    e,
                    "a polynomial coupling beyond degree 1 is not a mimic; ignored".into(),
                );
                continue;
            }
            let [c0, c1, ..] = coef;
            let Some(joint) = self.robot.joints.get_mut(follower) else {
                continue;
            };
            if joint.mimic.is_some() {
                self.warn(e, format!("joint '{j1}' already follows a joint; ignored"));
                continue;
            }
            // MuJoCo: qpos1 − ref1 = c0 + c1 (qpos2 − ref2); rows take qpos.
            joint.mimic = Some(MimicSpec {
                joint: j2.to_owned(),
                multiplier: c1,
                offset: c0 + r1 - c1 * r2,
            });
            joint.mimic_line = Some(e.line);
        }
        Ok(())
    }
}
