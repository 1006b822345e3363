//! Robot files held in memory: a file and the files beside it (a folder a person dropped on the
//! web page, where there is no disk), read as the CLI reads them from the disk. The format is
//! told as the CLI tells it: a `.xacro` name is expanded natively ([`crate::xacro`], includes,
//! `$(find PKG)` and `load_yaml` taken from the same files), then the content decides: MJCF when
//! the root element is `<mujoco>` (its `<include>`s from the same files), SDFormat when it is
//! `<sdf>`, else URDF.

use std::path::Path;
use std::sync::Arc;

use anyhow::Result;
pub use urdf_axes::mjcf::MemoryFiles;
use urdf_axes::{Chain, UrdfModel};

use crate::xacro::XacroOptions;

/// A robot file at `top` among `files`, with the xacro arguments and package folders to expand
/// it with (used only for a `.xacro` name).
#[derive(Clone, Debug)]
pub struct RobotFiles {
    /// The robot file's path in `files`.
    pub top: std::path::PathBuf,
    /// Every file given, by path.
    pub files: Arc<MemoryFiles>,
    /// Arguments and package folders of a xacro expansion (`files` is set from the above).
    pub xacro: XacroOptions,
}

impl RobotFiles {
    /// The robot file's name as messages show it (no folders: [`super::display_name`]).
    pub fn name(&self) -> String {
        super::display_name(&self.top.to_string_lossy())
    }

    /// The robot description's bytes: the file's own, or its xacro expansion, with the
    /// expansion's warnings (each as the CLI prints it after `urdf-dh: warning: `).
    ///
    /// # Errors
    /// The file is not among the files; an expansion error naming the file and line (an
    /// include or a package not among the files is named); a construct the native expansion
    /// refuses (there is no Python `xacro` to hand it to).
    pub fn bytes(&self) -> Result<(Vec<u8>, Vec<String>)> {
        let top = urdf_xacro::files::normalize(&self.top);
        let name = self.name();
        let Some(bytes) = self.files.get(&top) else {
            anyhow::bail!("{name}: cannot read the file: not among the files given");
        };
        if !top.to_string_lossy().ends_with(".xacro") {
            return Ok((bytes.clone(), Vec::new()));
        }
        let mut options = self.xacro.clone();
        options.files = Some(self.files.clone());
        crate::xacro::expand_in_memory(&top, &options)
    }

    /// The model and the chain `base` -> `tip` (defaults as [`super::load_chain_bytes`]), with
    /// the expansion's warnings.
    ///
    /// # Errors
    /// As [`RobotFiles::bytes`], then as [`super::load_chain_in`].
    pub fn load_chain(
        &self,
        base: Option<&str>,
        tip: Option<&str>,
    ) -> Result<(UrdfModel, Chain, Vec<String>)> {
        let (bytes, warnings) = self.bytes()?;
        let model = self.model_of(&bytes)?;
        let chain = model
            .chain(base, tip)
            .map_err(|e| super::chain_error(&self.name(), &model, e))?;
        Ok((model, chain, warnings))
    }

    /// The model of `bytes` (this file's, or its expansion), MJCF includes read from the files.
    ///
    /// # Errors
    /// As [`super::read_model`].
    pub fn model_of(&self, bytes: &[u8]) -> Result<UrdfModel> {
        let top = urdf_xacro::files::normalize(&self.top);
        let dir = top.parent().unwrap_or(Path::new(""));
        super::read_model_with(bytes, &self.name(), Some(dir), Some(&self.files))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn files(list: &[(&str, &str)]) -> Arc<MemoryFiles> {
        Arc::new(
            list.iter()
                .map(|(p, t)| (p.into(), t.as_bytes().to_vec()))
                .collect(),
        )
    }

    const ARM: &str = r#"<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="$(arg name)">
  <xacro:arg name="name" default="arm"/>
  <xacro:include filename="$(find arm_description)/urdf/joint.xacro"/>
  <link name="base"/><link name="l1"/><link name="l2"/>
  <xacro:joint n="j1" parent="base" child="l1" xyz="0 0 0.3" axis="0 0 1"/>
  <xacro:joint n="j2" parent="l1" child="l2" xyz="0 0.2 0" axis="0 1 0"/>
</robot>"#;

    const JOINT: &str = r#"<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="joint" params="n parent child xyz axis">
    <joint name="${n}" type="revolute"><parent link="${parent}"/><child link="${child}"/>
      <origin xyz="${xyz}"/><axis xyz="${axis}"/>
      <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  </xacro:macro>
</robot>"#;

    /// The options of `name:=NAME` (the root's name attribute is evaluated before the
    /// `<xacro:arg>` default is declared, as Python's xacro does).
    fn named(name: &str) -> XacroOptions {
        let mut o = XacroOptions::default();
        o.args.push(("name".into(), name.into()));
        o
    }

    #[test]
    fn expands_xacro_with_packages_and_args_from_the_files() {
        let given = RobotFiles {
            top: "/drop/arm_description/urdf/arm.urdf.xacro".into(),
            files: files(&[
                ("/drop/arm_description/urdf/arm.urdf.xacro", ARM),
                ("/drop/arm_description/urdf/joint.xacro", JOINT),
                (
                    "/drop/arm_description/package.xml",
                    "<package><name>arm_description</name></package>",
                ),
            ]),
            xacro: named("mine"),
        };
        let (model, chain, warnings) = given.load_chain(None, None).unwrap();
        assert_eq!(model.robot_name(), "mine");
        assert_eq!((chain.base(), chain.tip()), ("base", "l2"));
        assert_eq!(chain.axes().len(), 2);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn names_the_missing_package_and_file() {
        let mut given = RobotFiles {
            top: "/drop/arm.urdf.xacro".into(),
            files: files(&[("/drop/arm.urdf.xacro", ARM)]),
            xacro: named("arm"),
        };
        let e = format!("{:#}", given.bytes().unwrap_err());
        assert!(e.contains("package 'arm_description' not found"), "{e}");
        given.files = files(&[
            ("/drop/arm.urdf.xacro", ARM),
            (
                "/drop/arm_description/package.xml",
                "<package><name>arm_description</name></package>",
            ),
        ]);
        let e = format!("{:#}", given.bytes().unwrap_err());
        assert!(e.contains("joint.xacro"), "{e}");
    }

    #[test]
    fn reads_mjcf_includes_from_the_files() {
        let main = r#"<mujoco><include file="parts/body.xml"/></mujoco>"#;
        let body = r#"<mujoco><worldbody><body name="b"><joint name="j" axis="0 0 1"/>
            <body name="c" pos="0 0 0.2"><joint name="k" axis="0 1 0"/></body></body></worldbody></mujoco>"#;
        let given = RobotFiles {
            top: "/m/robot.xml".into(),
            files: files(&[("/m/robot.xml", main), ("/m/parts/body.xml", body)]),
            xacro: XacroOptions::default(),
        };
        let (model, chain, _) = given.load_chain(None, Some("c")).unwrap();
        assert_eq!(model.format_name(), "MJCF");
        assert_eq!(chain.axes().len(), 2);
        let alone = RobotFiles {
            files: files(&[("/m/robot.xml", main)]),
            ..given
        };
        let e = format!("{:#}", alone.load_chain(None, None).unwrap_err());
        assert!(e.contains("parts/body.xml"), "{e}");
    }
}
