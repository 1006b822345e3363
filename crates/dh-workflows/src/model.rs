//! The robot model of the measured-data commands (`--model` of `calibrate`, `predict`, ...):
//! [`load_model`] reads a URDF (its chain extracted and verified, as `urdf-dh extract` does) or
//! a DH sheet into a [`LoadedModel`], with the columns a measurement file needs
//! ([`LoadedModel::measured_joints`]) and the coupling of their values
//! ([`LoadedModel::couple`]).
//!
//! Frames and units: the table is in metres and radians; `base` is DH frame 0 in the base link
//! frame, `tool` the tip link frame in the last DH frame.

use anyhow::{Context, Result};
use dh_calib::data::Measurements;
use dh_core::{Convention, DhTable, JointKind, Tolerance};

use crate::error::hinted;
use crate::input::{display_name, load_chain, read_robot_bytes, urdf_warnings, utf8_text};
use crate::sheet::Sheet;
use crate::tree_sheet::TreeSheet;
use crate::units::{AngleUnit, LengthUnit};

/// A robot model given with `--model`.
#[derive(Clone, Debug)]
pub struct LoadedModel {
    /// The table (metres, radians) with base and tool.
    pub table: DhTable,
    /// The file name (no directories).
    pub origin: String,
    /// Robot name, when the file gives one.
    pub robot: Option<String>,
    /// Units a written-back sheet should use: the sheet's own, metres and radians for a URDF.
    pub units: (LengthUnit, AngleUnit),
    /// Warnings about the model (snapped axes, suspicious units).
    pub warnings: Vec<String>,
    /// Base and tip link names: the URDF chain's, `base_link` and `tool0` for a sheet.
    pub links: (String, String),
    /// Coupled joints of a sheet (`coupled`): `(joint, [(driver, coefficient)])`.
    pub coupled: Vec<(String, Vec<(String, f64)>)>,
}

impl LoadedModel {
    /// A tree sheet's model as the measured-data code takes it: every row of the tree in joint
    /// order (trunk, then each branch), for the columns a measurement file needs and the
    /// coupling of its values ([`LoadedModel::measured_joints`], [`LoadedModel::couple`]).
    pub fn of_tree(sheet: &TreeSheet, origin: &str) -> LoadedModel {
        LoadedModel {
            table: sheet.tree.joint_table(),
            origin: origin.to_string(),
            robot: sheet.robot.clone(),
            units: (sheet.length_unit, sheet.angle_unit),
            warnings: sheet.warnings.clone(),
            links: ("base_link".into(), "tool0".into()),
            coupled: sheet.coupled.clone(),
        }
    }

    /// The columns a measurement file needs, in row order: every row but the mimic ones (which
    /// follow their driver) and the coupled ones, plus the drivers of both (a mimic's driver
    /// may be a joint off the chain, such as a telescopic column's own joint).
    pub fn measured_joints(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        let mut push = |n: &str| {
            if !out.iter().any(|o| o == n) {
                out.push(n.to_string());
            }
        };
        for r in &self.table.rows {
            let coupled = self.coupled.iter().find(|(j, _)| j == &r.name);
            match (&r.mimic, coupled) {
                (Some(m), _) => push(&m.joint),
                (None, Some((_, terms))) => terms.iter().for_each(|(d, _)| push(d)),
                (None, None) => push(&r.name),
            }
        }
        out
    }

    /// Names of the prismatic joints among the rows and the drivers of prismatic mimic rows.
    pub fn prismatic(&self) -> Vec<String> {
        let mut p = prismatic(&self.table);
        for r in &self.table.rows {
            if let (JointKind::Prismatic, Some(m)) = (r.kind, &r.mimic) {
                if !p.contains(&m.joint) {
                    p.push(m.joint.clone());
                }
            }
        }
        p
    }

    /// Replaces (or adds) the coupled joints' values in `data`: value = Σ coefficient × driver,
    /// from the values as read.
    ///
    /// # Errors
    /// A driver without a column.
    pub fn couple(&self, data: &mut Measurements) -> Result<()> {
        if self.coupled.is_empty() {
            return Ok(());
        }
        let mut terms = Vec::new();
        for (joint, t) in &self.coupled {
            let cols = t
                .iter()
                .map(|(d, c)| {
                    data.joint_names
                        .iter()
                        .position(|n| n == d)
                        .map(|i| (i, *c))
                        .with_context(|| {
                            format!("coupled joint '{joint}': the data has no column '{d}'")
                        })
                })
                .collect::<Result<Vec<_>>>()?;
            terms.push((joint.clone(), cols));
        }
        let mut targets = Vec::new();
        for (joint, _) in &terms {
            let at = match data.joint_names.iter().position(|n| n == joint) {
                Some(i) => i,
                None => {
                    data.joint_names.push(joint.clone());
                    data.joint_names.len() - 1
                }
            };
            targets.push(at);
        }
        for s in &mut data.samples {
            let read = &s.q;
            let mut q = read.to_vec();
            q.resize(data.joint_names.len(), 0.0);
            for ((_, cols), &at) in terms.iter().zip(&targets) {
                q[at] = cols
                    .iter()
                    .map(|&(i, c)| c * read.get(i).copied().unwrap_or(0.0))
                    .sum();
            }
            s.q = q.into();
        }
        Ok(())
    }

    /// The inverse of [`LoadedModel::couple`] for simulated data, whose values are the rows'
    /// (serial) ones: each coupled joint's column becomes the value its controller reports,
    /// `(serial − Σ other terms) / own coefficient`, in row order.
    ///
    /// # Errors
    /// A coupled joint without a term of its own (its value follows from the others, which
    /// random poses do not respect), a zero own coefficient, or a driver coupled later in the
    /// chain.
    pub fn uncouple(&self, data: &mut Measurements) -> Result<()> {
        let col = |n: &str| data.joint_names.iter().position(|j| j == n);
        let mut done: Vec<&str> = Vec::new();
        let mut plan = Vec::new();
        for (joint, terms) in &self.coupled {
            let own = terms.iter().find(|(d, _)| d == joint).map(|(_, c)| *c);
            let own = match own {
                Some(c) if c != 0.0 => c,
                _ => {
                    return Err(hinted(
                        format!("coupled joint '{joint}' has no term of its own, so random joint values cannot respect its coupling"),
                        "simulate a model without this coupling (drop its 'coupled' entry)",
                    ))
                }
            };
            let at = col(joint).with_context(|| format!("no column '{joint}'"))?;
            let mut others = Vec::new();
            for (d, c) in terms.iter().filter(|(d, _)| d != joint) {
                if self.coupled.iter().any(|(j, _)| j == d) && !done.contains(&d.as_str()) {
                    anyhow::bail!("coupled joint '{joint}': driver '{d}' is coupled later in the chain; cannot invert");
                }
                others.push((col(d).with_context(|| format!("no column '{d}'"))?, *c));
            }
            plan.push((at, own, others));
            done.push(joint);
        }
        for s in &mut data.samples {
            let mut q = s.q.to_vec();
            for (at, own, others) in &plan {
                let rest: f64 = others.iter().map(|&(i, c)| c * q[i]).sum();
                q[*at] = (q[*at] - rest) / own;
            }
            s.q = q.into();
        }
        Ok(())
    }
}

/// Rows of `table` that take a column in a measurement file (mimic rows follow their driver).
pub fn measured_joints(table: &DhTable) -> Vec<String> {
    table
        .rows
        .iter()
        .filter(|r| r.mimic.is_none())
        .map(|r| r.name.clone())
        .collect()
}

/// Names of the prismatic rows of `table`.
pub fn prismatic(table: &DhTable) -> Vec<String> {
    table
        .rows
        .iter()
        .filter(|r| r.kind == JointKind::Prismatic)
        .map(|r| r.name.clone())
        .collect()
}

/// Whether `path` names a URDF rather than a sheet: by extension, else by the first character
/// of `text` (`<` for XML).
pub fn is_urdf(path: &str, text: &str) -> bool {
    let lower = path.to_ascii_lowercase();
    if lower.ends_with(".urdf") || lower.ends_with(".xacro") || lower.ends_with(".xml") {
        return true;
    }
    if lower.ends_with(".yaml") || lower.ends_with(".yml") || lower.ends_with(".json") {
        return false;
    }
    text.trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with('<')
}

/// A DH sheet as a model, and the warning for a command that cannot use its effects.
pub struct SheetModel {
    /// The model.
    pub loaded: LoadedModel,
    /// The warning naming the sheet's effects, `None` without effects.
    pub effects_warning: Option<String>,
}

/// The model of a DH sheet's `text` (`origin` names it in messages).
///
/// # Errors
/// As [`Sheet::parse`].
pub fn sheet_model(text: &str, origin: &str) -> Result<SheetModel> {
    let sheet = Sheet::parse(text, origin)?;
    let effects_warning = sheet.effects_warning(
        origin,
        "the model is its DH values; name effects with --effects (calibrate) or --effect (simulate)",
    );
    Ok(SheetModel {
        loaded: LoadedModel {
            table: sheet.table,
            origin: origin.to_string(),
            robot: sheet.robot,
            units: (sheet.length_unit, sheet.angle_unit),
            warnings: sheet.warnings,
            links: ("base_link".into(), "tool0".into()),
            coupled: sheet.coupled,
        },
        effects_warning,
    })
}

/// [`load_model`], its warnings written to `err` as `urdf-dh: warning:` lines (as every reader
/// of this crate notes them).
///
/// # Errors
/// As [`load_model`]; a failed write to `err`.
pub fn load_model_noting(
    path: &str,
    base: Option<&str>,
    tip: Option<&str>,
    convention: Convention,
    err: &mut dyn std::io::Write,
) -> Result<LoadedModel> {
    let model = load_model(path, base, tip, convention)?;
    for w in &model.warnings {
        writeln!(err, "urdf-dh: warning: {w}")?;
    }
    Ok(model)
}

/// Loads `--model`: a URDF (chain from `base` to `tip`, extracted in `convention` and verified
/// as `extract` does) or a DH sheet (YAML or JSON; `base`, `tip` and `convention` do not apply).
///
/// # Errors
/// Unreadable or invalid file, a chain that cannot be chosen or extracted, a URDF whose
/// extraction fails its own verification.
pub fn load_model(
    path: &str,
    base: Option<&str>,
    tip: Option<&str>,
    convention: Convention,
) -> Result<LoadedModel> {
    let origin = display_name(path);
    // A .xacro file is expanded by load_chain; anything else is read once here.
    let text = if path.to_ascii_lowercase().ends_with(".xacro") {
        None
    } else {
        Some(utf8_text(path, read_robot_bytes(path)?)?)
    };
    let urdf = text.as_deref().is_none_or(|t| is_urdf(path, t));
    if urdf && path == "-" {
        return Err(hinted(
            "<stdin>: a URDF model must be given as a file",
            "save it to a file, or extract a sheet first: urdf-dh extract - --format yaml > model.yaml",
        ));
    }
    if !urdf {
        if base.is_some() || tip.is_some() {
            return Err(hinted(
                format!("{origin}: --base and --tip choose a chain of a URDF, but the model is a DH sheet"),
                "drop --base/--tip, or give the URDF as --model",
            ));
        }
        let SheetModel {
            mut loaded,
            effects_warning,
        } = sheet_model(text.as_deref().unwrap_or_default(), &origin)?;
        loaded.warnings.extend(effects_warning);
        return Ok(loaded);
    }
    let (urdf_model, chain) = load_chain(path, base, tip)?;
    let extraction = dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        Tolerance::default(),
        convention,
    )
    .with_context(|| format!("{origin}: extraction failed"))?;
    let deviation = dh_core::compare(&extraction.table, |q| chain.fk(q), 1000, 0)?;
    if deviation.max_position_error > extraction.bound.position
        || deviation.max_orientation_error > extraction.bound.orientation
    {
        anyhow::bail!(
            "{origin}: the DH table extracted from the URDF fails its own verification; run 'urdf-dh extract {}' for details",
            crate::text::quote(path)
        );
    }
    Ok(LoadedModel {
        table: extraction.table,
        origin,
        robot: Some(urdf_model.robot_name().to_string()),
        units: (LengthUnit::M, AngleUnit::Rad),
        warnings: urdf_warnings(path, &urdf_model, &chain)
            .into_iter()
            .chain(extraction.warnings.iter().map(|w| w.to_string()))
            .collect(),
        links: (chain.base().to_string(), chain.tip().to_string()),
        coupled: Vec::new(),
    })
}
