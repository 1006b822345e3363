//! The frame graph of an SDFormat document: every world, model, link, joint and `<frame>`
//! with its scoped name, the frame its pose is relative to, and its pose; then every frame's
//! pose in the world frame.
//!
//! # Names and scopes
//! A single model (`<sdf><model>`, or a world holding one model) keeps its names as written.
//! In a world of several models every name takes its model's scope (`arm::link`), and inside a
//! nested model its name's (`arm::gripper::finger`), as libsdformat names them. A name is
//! looked up in the scope of the element that writes it: `__model__` is that scope's model
//! frame, `world` the world frame, and `inner::link` reaches into a nested model.
//!
//! # Default frames (sdformat.org, "Pose frame semantics", 1.4 legacy and 1.7 proposal)
//! - link: its model's frame; joint: its child's frame (the child link; from 1.8 the child may
//!   be a `<frame>`); nested model: its parent model's frame; top-level model: the world;
//! - from 1.7: `<pose relative_to>` overrides these; a `<frame>`'s pose defaults to its
//!   `attached_to`, which defaults to the model frame.

use std::collections::HashMap;

use nalgebra::Isometry3;
use roxmltree::Node;

use super::line_of;
use super::pose::{read_pose, sdf_error, Pose, Version};
use crate::UrdfError;

/// Deepest nesting of models accepted (real files nest two or three).
const MAX_MODEL_DEPTH: usize = 32;

/// What a frame belongs to.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Kind {
    /// The world frame.
    World,
    /// A model's frame; its canonical link (scoped), when it has links.
    Model { canonical: Option<String> },
    /// A link's frame.
    Link,
    /// A joint's frame; its child (scoped frame or link name).
    Joint { child: String },
    /// A `<frame>`, attached to a (scoped) frame.
    Frame { attached_to: String },
}

/// One frame of the graph.
#[derive(Clone, Debug)]
pub(crate) struct Frame {
    /// Scoped name.
    pub name: String,
    /// 1-based line of its element.
    pub line: usize,
    pub kind: Kind,
    /// The (scoped) frame its pose is relative to; `None` for the world.
    pub parent: Option<String>,
    /// Its pose in `parent`.
    pub pose: Isometry3<f64>,
    /// Line of its `<pose>` (of the element when there is none).
    pub pose_line: usize,
}

/// The private key prefix of a joint's frame before sdformat 1.7 (see
/// [`JointSpec::frame_key`]); never shown in a message ([`Frame::shown`]).
const OLD_JOINT_KEY: &str = "\u{0}joint ";

impl Frame {
    /// The frame as a message names it: its element and its scoped name as written, e.g.
    /// `joint 'wrist_1'` (never the private key of a joint before 1.7).
    pub(crate) fn shown(&self) -> String {
        let element = match self.kind {
            Kind::World => "world",
            Kind::Model { .. } => "model",
            Kind::Link => "link",
            Kind::Joint { .. } => "joint",
            Kind::Frame { .. } => "frame",
        };
        let name = self.name.strip_prefix(OLD_JOINT_KEY).unwrap_or(&self.name);
        format!("{element} '{name}'")
    }
}

/// A `<joint>` as written, its names scoped.
#[derive(Clone, Debug)]
pub(crate) struct JointSpec<'a, 'i> {
    pub name: String,
    /// Its frame's key in the graph: its name from 1.7 on; a private key before, when joints
    /// and links had names of their own (a UR10 of 1.5 has a link and a joint `wrist_1`).
    pub frame_key: String,
    pub node: Node<'a, 'i>,
    pub parent: String,
    pub parent_line: usize,
    pub child: String,
    pub child_line: usize,
    /// The model frame of the joint's scope.
    pub model_frame: String,
    /// The scope prefix, for names the axis writes.
    pub prefix: String,
}

/// A `<link>` as written.
#[derive(Clone, Debug)]
pub(crate) struct LinkSpec<'a, 'i> {
    pub name: String,
    pub node: Node<'a, 'i>,
}

/// Everything collected from the document.
#[derive(Debug, Default)]
pub(crate) struct Graph<'a, 'i> {
    pub frames: Vec<Frame>,
    pub index: HashMap<String, usize>,
    pub links: Vec<LinkSpec<'a, 'i>>,
    pub joints: Vec<JointSpec<'a, 'i>>,
    /// Warnings: (element, line, message).
    pub warnings: Vec<(String, usize, String)>,
}

/// The name `name` written in the scope `prefix` (whose model frame is `model_frame`).
pub(crate) fn scoped(prefix: &str, model_frame: &str, name: &str) -> String {
    match name {
        "__model__" => model_frame.to_owned(),
        "world" => "world".to_owned(),
        _ => format!("{prefix}{name}"),
    }
}

impl<'a, 'i> Graph<'a, 'i> {
    /// Collects the frames of the `<model>` or `<world>` children of `<sdf>`.
    ///
    /// # Errors
    /// [`UrdfError::Sdf`] for a duplicate name in one scope, a malformed pose, a link or joint
    /// without a name, a joint without parent or child, or models nested too deep.
    pub fn collect(sdf: Node<'a, 'i>, version: Version) -> Result<Self, UrdfError> {
        let mut g = Graph::default();
        g.add(Frame {
            name: "world".into(),
            line: line_of(sdf),
            kind: Kind::World,
            parent: None,
            pose: Isometry3::identity(),
            pose_line: line_of(sdf),
        })?;
        let worlds: Vec<Node> = sdf.children().filter(|c| c.has_tag_name("world")).collect();
        let mut models: Vec<Node> = sdf.children().filter(|c| c.has_tag_name("model")).collect();
        for w in &worlds {
            models.extend(w.children().filter(|c| c.has_tag_name("model")));
            g.warn_includes(*w);
        }
        let scoped_models = models.len() > 1;
        for m in models {
            let name = m.attribute("name").unwrap_or("").to_owned();
            let (prefix, frame) = if scoped_models {
                (format!("{name}::"), name.clone())
            } else {
                (String::new(), "__model__".to_owned())
            };
            let pose = read_pose(m, version, &mut |l, msg| {
                g.warnings.push((format!("model '{name}'"), l, msg))
            })?;
            let parent = match &pose.relative_to {
                None => "world".to_owned(),
                Some(r) => scoped("", "world", r),
            };
            g.model(m, version, prefix, frame, parent, pose, 0)?;
        }
        Ok(g)
    }

    fn warn_includes(&mut self, scope: Node) {
        for inc in scope.children().filter(|c| c.has_tag_name("include")) {
            let uri = inc
                .children()
                .find(|c| c.has_tag_name("uri"))
                .and_then(|u| u.text())
                .unwrap_or("")
                .trim()
                .to_owned();
            self.warnings.push((
                "<include>".into(),
                line_of(inc),
                format!("'{uri}' is not expanded (urdf-dh reads one file); its links are not in the model"),
            ));
        }
    }

    fn add(&mut self, frame: Frame) -> Result<(), UrdfError> {
        if let Some(&first) = self.index.get(&frame.name) {
            let first_line = self.frames.get(first).map_or(0, |f| f.line);
            return Err(UrdfError::Sdf {
                message: format!(
                    "{}: expected unique names in a model (links, joints, frames and nested models share one scope), found it defined again (first at line {first_line})",
                    frame.shown()
                ),
                line: Some(frame.line),
            });
        }
        self.index.insert(frame.name.clone(), self.frames.len());
        self.frames.push(frame);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn model(
        &mut self,
        m: Node<'a, 'i>,
        version: Version,
        prefix: String,
        frame: String,
        parent: String,
        pose: Pose,
        depth: usize,
    ) -> Result<(), UrdfError> {
        if depth > MAX_MODEL_DEPTH {
            return Err(sdf_error(
                m,
                format!("expected models nested at most {MAX_MODEL_DEPTH} deep, found deeper"),
            ));
        }
        let canonical = m
            .attribute("canonical_link")
            .map(|c| scoped(&prefix, &frame, c))
            .or_else(|| {
                m.children()
                    .find(|c| c.has_tag_name("link"))
                    .and_then(|l| l.attribute("name"))
                    .map(|n| format!("{prefix}{n}"))
            });
        self.add(Frame {
            name: frame.clone(),
            line: line_of(m),
            kind: Kind::Model { canonical },
            parent: Some(parent),
            pose: pose.transform,
            pose_line: pose.line,
        })?;
        self.warn_includes(m);
        if m.attribute("placement_frame").is_some() {
            self.warnings.push((
                format!("model '{frame}'"),
                line_of(m),
                "placement_frame is ignored: the model's pose places its model frame".into(),
            ));
        }
        let modern = version.has_frame_semantics();
        let named = |e: Node, what: &str| -> Result<String, UrdfError> {
            e.attribute("name").map(str::to_owned).ok_or_else(|| {
                sdf_error(
                    e,
                    format!("<{what}>: expected attribute 'name', found none"),
                )
            })
        };
        for e in m.children().filter(Node::is_element) {
            let tag = e.tag_name().name();
            match tag {
                "link" | "frame" | "joint" | "model" => {}
                _ => continue,
            }
            let local = named(e, tag)?;
            let name = format!("{prefix}{local}");
            let mut warns = Vec::new();
            let pose = read_pose(e, version, &mut |l, msg| warns.push((l, msg)))?;
            for (l, msg) in warns {
                self.warnings.push((format!("{tag} '{name}'"), l, msg));
            }
            let relative = |default: String| match (&pose.relative_to, modern) {
                (Some(r), true) => scoped(&prefix, &frame, r),
                _ => default,
            };
            match tag {
                "link" => {
                    self.add(Frame {
                        name: name.clone(),
                        line: line_of(e),
                        kind: Kind::Link,
                        parent: Some(relative(frame.clone())),
                        pose: pose.transform,
                        pose_line: pose.line,
                    })?;
                    self.links.push(LinkSpec { name, node: e });
                }
                "frame" if !modern => self.warnings.push((
                    format!("frame '{name}'"),
                    line_of(e),
                    "<frame> has no meaning before sdformat 1.7; ignored".into(),
                )),
                "frame" => {
                    let attached_to = e
                        .attribute("attached_to")
                        .map(str::trim)
                        .filter(|a| !a.is_empty())
                        .map_or_else(|| frame.clone(), |a| scoped(&prefix, &frame, a));
                    self.add(Frame {
                        name,
                        line: line_of(e),
                        kind: Kind::Frame {
                            attached_to: attached_to.clone(),
                        },
                        parent: Some(relative(attached_to)),
                        pose: pose.transform,
                        pose_line: pose.line,
                    })?;
                }
                "joint" => {
                    let end = |role: &str| -> Result<(String, usize), UrdfError> {
                        let el = e.children().find(|c| c.has_tag_name(role)).ok_or_else(|| {
                            sdf_error(
                                e,
                                format!("joint '{name}': expected a <{role}> element, found none"),
                            )
                        })?;
                        let text = el.text().unwrap_or("").trim();
                        if text.is_empty() {
                            return Err(sdf_error(
                                el,
                                format!("joint '{name}', <{role}>: expected a link or frame name, found nothing"),
                            ));
                        }
                        Ok((scoped(&prefix, &frame, text), line_of(el)))
                    };
                    let (parent_name, parent_line) = end("parent")?;
                    let (child, child_line) = end("child")?;
                    let frame_key = if modern {
                        name.clone()
                    } else {
                        format!("{OLD_JOINT_KEY}{name}")
                    };
                    self.add(Frame {
                        name: frame_key.clone(),
                        line: line_of(e),
                        kind: Kind::Joint {
                            child: child.clone(),
                        },
                        parent: Some(relative(child.clone())),
                        pose: pose.transform,
                        pose_line: pose.line,
                    })?;
                    self.joints.push(JointSpec {
                        name,
                        frame_key,
                        node: e,
                        parent: parent_name,
                        parent_line,
                        child,
                        child_line,
                        model_frame: frame.clone(),
                        prefix: prefix.clone(),
                    });
                }
                _ => {
                    let inner_prefix = format!("{name}::");
                    let parent = relative(frame.clone());
                    self.model(e, version, inner_prefix, name, parent, pose, depth + 1)?;
                }
            }
        }
        Ok(())
    }

    /// The frame named `name`.
    pub fn get(&self, name: &str) -> Option<&Frame> {
        self.index.get(name).and_then(|&i| self.frames.get(i))
    }

    /// The pose of every frame in the world frame, in the order of [`Graph::frames`].
    ///
    /// # Errors
    /// [`UrdfError::Sdf`] for a pose relative to a frame the scope does not define, or a cycle
    /// of `relative_to`.
    pub fn world_poses(&self) -> Result<Vec<Isometry3<f64>>, UrdfError> {
        let n = self.frames.len();
        let mut done: Vec<Option<Isometry3<f64>>> = vec![None; n];
        for start in 0..n {
            let mut path = Vec::new();
            let mut on_path = vec![false; n];
            let mut k = start;
            let base = loop {
                if let Some(p) = done.get(k).copied().flatten() {
                    break p;
                }
                let Some(f) = self.frames.get(k) else {
                    break Isometry3::identity();
                };
                if on_path.get(k).copied().unwrap_or(false) {
                    return Err(UrdfError::Sdf {
                        message: format!(
                            "{}: expected poses that lead to the world frame, found a cycle of relative_to through it",
                            f.shown()
                        ),
                        line: Some(f.pose_line),
                    });
                }
                if let Some(slot) = on_path.get_mut(k) {
                    *slot = true;
                }
                path.push(k);
                match &f.parent {
                    None => break Isometry3::identity(),
                    Some(p) => match self.index.get(p) {
                        Some(&next) => k = next,
                        None => {
                            return Err(UrdfError::Sdf {
                                message: match &f.kind {
                                    Kind::Joint { child } if child == p => format!(
                                        "{}: expected its <child> to name a link or frame of its model, found '{p}', which no link, joint, frame or model defines",
                                        f.shown()
                                    ),
                                    _ => format!(
                                        "{}: expected its pose relative to a frame of its model, found '{p}', which no link, joint, frame or model defines",
                                        f.shown()
                                    ),
                                },
                                line: Some(f.pose_line),
                            })
                        }
                    },
                }
            };
            // Compose back down the path: the last element is relative to `base`.
            let mut pose = base;
            for &k in path.iter().rev() {
                let Some(f) = self.frames.get(k) else {
                    continue;
                };
                if f.parent.is_some() {
                    pose *= f.pose;
                }
                if let Some(slot) = done.get_mut(k) {
                    *slot = Some(pose);
                }
            }
        }
        Ok(done
            .into_iter()
            .map(|p| p.unwrap_or_else(Isometry3::identity))
            .collect())
    }

    /// The link a frame is attached to: itself for a link, its `attached_to`'s for a
    /// `<frame>`, its child's for a joint, its canonical link's for a model; `None` for the
    /// world or a name no element defines.
    pub fn attached_link(&self, name: &str) -> Option<String> {
        let mut name = name.to_owned();
        for _ in 0..=self.frames.len() {
            let f = self.get(&name)?;
            name = match &f.kind {
                Kind::Link => return Some(name),
                Kind::World => return None,
                Kind::Frame { attached_to } => attached_to.clone(),
                Kind::Joint { child } => child.clone(),
                Kind::Model { canonical } => canonical.clone()?,
            };
        }
        None
    }
}
