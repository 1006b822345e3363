//! What the page's 3-D view draws: the URDF's frames along a chain and the DH frames of its
//! table at the same joint values, both from the library (`dh_workflows::input::Chain::link_poses`,
//! `dh_workflows::geometry::DhTable::frames`, `DhTable::common_normals`), in the base link frame, metres.
//!
//! Poses go to JavaScript as 4x4 homogeneous matrices in column-major order (16 numbers, as
//! three.js's `Matrix4.fromArray` reads them).

use std::collections::HashMap;

use dh_workflows::extract::{default_samples, prove_extracted_with, Extracted};
use dh_workflows::geometry::JointKind;
use dh_workflows::input::RobotFiles;
use dh_workflows::Format;
use nalgebra::Isometry3;
use serde::Serialize;
use wasm_bindgen::prelude::*;

use crate::{js_error, ExtractOptionsDoc};

/// A pose as 16 numbers, column-major.
fn matrix(p: &Isometry3<f64>) -> Vec<f64> {
    p.to_homogeneous().as_slice().to_vec()
}

/// One link of the tree.
#[derive(Serialize)]
struct LinkDoc<'a> {
    name: &'a str,
    parent: Option<&'a str>,
    joint: Option<&'a str>,
}

/// The default chain.
#[derive(Serialize)]
struct ChainDoc<'a> {
    base: &'a str,
    tip: &'a str,
}

/// The tree of [`crate::tree`].
#[derive(Serialize)]
struct TreeDoc<'a> {
    robot: &'a str,
    format: &'a str,
    root: &'a str,
    links: Vec<LinkDoc<'a>>,
    default: Option<ChainDoc<'a>>,
    default_error: Option<String>,
}

/// See [`crate::tree`].
pub(crate) fn tree(robot: &RobotFiles) -> anyhow::Result<String> {
    let name = robot.name();
    let (bytes, _warnings) = robot.bytes()?;
    let model = robot.model_of(&bytes)?;
    let links = model
        .links()
        .into_iter()
        .map(|link| {
            let parent = model.parent_joint(link);
            LinkDoc {
                name: link,
                parent: parent.map(|p| p.1),
                joint: parent.map(|p| p.0),
            }
        })
        .collect();
    let chain = model.chain(None, None);
    let (default, default_error) = match &chain {
        Ok(c) => (
            Some(ChainDoc {
                base: c.base(),
                tip: c.tip(),
            }),
            None,
        ),
        Err(e) => (
            None,
            Some(format!(
                "{:#}",
                dh_workflows::input::chain_error(&name, &model, e.clone())
            )),
        ),
    };
    let doc = TreeDoc {
        robot: model.robot_name(),
        format: model.format_name(),
        root: model.root_link(),
        links,
        default,
        default_error,
    };
    Ok(serde_json::to_string(&doc)?)
}

/// One moving joint, for its slider.
#[derive(Serialize)]
struct JointDoc<'a> {
    name: &'a str,
    /// `revolute` (radians) or `prismatic` (metres).
    kind: &'static str,
    /// Lower limit, `null` for a continuous joint.
    lower: Option<f64>,
    /// Upper limit, `null` for a continuous joint.
    upper: Option<f64>,
}

/// The scene at one set of joint values.
#[derive(Serialize)]
struct SceneDoc {
    /// The URDF's child link frame of each moving joint, then the tip link frame.
    urdf: Vec<Vec<f64>>,
    /// Each joint axis at `q`: a point and the unit direction.
    axes: Vec<[f64; 6]>,
    /// DH frames `0..=n`.
    dh: Vec<Vec<f64>>,
    /// Each row's common normal: start and end points.
    normals: Vec<[f64; 6]>,
    /// The DH table's tip pose (`dh[n]` times the tool).
    dh_tip: Vec<f64>,
}

/// One extraction of a chain (its table in SI units, its sheet in the units asked for), made once
/// per file and settings: the page's table, texts, warnings and sliders all read it.
#[wasm_bindgen]
pub struct Robot {
    ex: Extracted,
    samples: usize,
    seed: u64,
    /// The robot file's tip pose at each proof sample (by the bits of the joint values): the
    /// proofs of the texts in several formats draw the same samples, so the robot file's side
    /// is computed once.
    poses: HashMap<Vec<u64>, Isometry3<f64>>,
}

impl Robot {
    /// The extraction `o` describes.
    pub(crate) fn extract(text: &str, o: &ExtractOptionsDoc) -> Result<Robot, JsError> {
        let ex = crate::extracted(text, o).map_err(js_error)?;
        let samples = o
            .samples
            .unwrap_or_else(|| default_samples(ex.extraction.table.rows.len()));
        Ok(Robot {
            ex,
            samples,
            seed: o.seed,
            poses: HashMap::new(),
        })
    }

    /// The text `urdf-dh extract --format F` prints, proved as written.
    pub(crate) fn output_as(&mut self, format: Format) -> anyhow::Result<String> {
        let poses = &mut self.poses;
        let (text, _passed) =
            prove_extracted_with(&mut self.ex, format, self.samples, self.seed, |chain, q| {
                let key = q.iter().map(|v| v.to_bits()).collect();
                *poses.entry(key).or_insert_with(|| chain.fk(q))
            })?;
        Ok(text)
    }
}

#[wasm_bindgen]
impl Robot {
    /// Extracts the chain chosen by `options` (those of [`crate::extract`]; the format does not
    /// matter here: [`Robot::output`] takes it).
    ///
    /// # Errors
    /// As [`crate::extract`].
    #[wasm_bindgen(constructor)]
    pub fn new(text: &str, options: &str) -> Result<Robot, JsError> {
        let o = ExtractOptionsDoc::parse(options).map_err(js_error)?;
        Robot::extract(text, &o)
    }

    /// The text `urdf-dh extract --format FORMAT` prints (`text`, `yaml`, `json`, `csv`,
    /// `markdown`), proved as written.
    ///
    /// # Errors
    /// An unknown format; a writer bug (the text does not read back).
    pub fn output(&mut self, format: &str) -> Result<String, JsError> {
        let format = crate::options::format_named(format).map_err(js_error)?;
        self.output_as(format).map_err(js_error)
    }

    /// The warnings `urdf-dh extract` prints on standard error (without the
    /// `urdf-dh: warning: ` prefix), as a JSON array of strings.
    ///
    /// # Errors
    /// None expected (serialising strings).
    pub fn warnings(&self) -> Result<String, JsError> {
        let all: Vec<String> = self
            .ex
            .urdf_warnings
            .iter()
            .cloned()
            .chain(self.ex.extraction.warnings.iter().map(|w| w.to_string()))
            .collect();
        serde_json::to_string(&all).map_err(|e| JsError::new(&e.to_string()))
    }

    /// The moving joints as JSON `[{name, kind, lower, upper}]`, in row order.
    ///
    /// # Errors
    /// None expected (serialising plain data).
    pub fn joints(&self) -> Result<String, JsError> {
        let joints: Vec<JointDoc> = self
            .ex
            .chain
            .axes()
            .iter()
            .map(|a| JointDoc {
                name: &a.name,
                kind: match a.kind {
                    JointKind::Revolute => "revolute",
                    JointKind::Prismatic => "prismatic",
                },
                lower: a.limits.map(|l| l.lower),
                upper: a.limits.map(|l| l.upper),
            })
            .collect();
        serde_json::to_string(&joints).map_err(|e| JsError::new(&e.to_string()))
    }

    /// Both forward kinematics at joint values `q` (one per row; radians, metres) as JSON
    /// `{urdf, axes, dh, normals, dh_tip}` (see the module's documentation for the layout).
    ///
    /// # Errors
    /// `q` of the wrong length or not finite.
    pub fn fk(&self, q: &[f64]) -> Result<String, JsError> {
        let run = || -> anyhow::Result<String> {
            let (chain, table) = (&self.ex.chain, &self.ex.extraction.table);
            let urdf = chain.link_poses(q)?;
            let axes = chain.axis_lines(q)?;
            let dh = table.frames(q)?;
            let normals = table.common_normals(q)?;
            let dh_tip = table.fk(q)?;
            let six = |a: nalgebra::Vector3<f64>, b: nalgebra::Vector3<f64>| {
                [a.x, a.y, a.z, b.x, b.y, b.z]
            };
            let doc = SceneDoc {
                urdf: urdf.iter().map(matrix).collect(),
                axes: axes.iter().map(|l| six(l.point(), l.direction())).collect(),
                dh: dh.iter().map(matrix).collect(),
                normals: normals.iter().map(|[a, b]| six(*a, *b)).collect(),
                dh_tip: matrix(&dh_tip),
            };
            Ok(serde_json::to_string(&doc)?)
        };
        run().map_err(js_error)
    }
}
