//! The options of every command that reads a robot file, for `.xacro` files: `--xacro-arg
//! NAME:=VALUE` and `--package NAME=DIR`, handed to the native expansion
//! ([`dh_workflows::xacro`]).

use clap::Args;

/// `--xacro-arg` and `--package`.
#[derive(Debug, Default, Args)]
pub struct XacroCli {
    /// A xacro argument of a .xacro robot, as `xacro FILE NAME:=VALUE` takes it (repeatable).
    #[arg(long = "xacro-arg", value_name = "NAME:=VALUE")]
    pub xacro_args: Vec<String>,
    /// The folder of ROS package NAME for `$(find NAME)` in a .xacro robot, before
    /// ROS_PACKAGE_PATH and AMENT_PREFIX_PATH (repeatable).
    #[arg(long = "package", value_name = "NAME=DIR")]
    pub packages: Vec<String>,
}

impl XacroCli {
    /// The expansion's options.
    ///
    /// # Errors
    /// A malformed `--xacro-arg` or `--package`.
    pub fn options(&self) -> anyhow::Result<dh_workflows::xacro::XacroOptions> {
        let mut o = dh_workflows::xacro::XacroOptions::default();
        for a in &self.xacro_args {
            o.add_arg(a)
                .map_err(|e| anyhow::anyhow!("--xacro-arg: {e}"))?;
        }
        for p in &self.packages {
            o.add_package(p)
                .map_err(|e| anyhow::anyhow!("--package: {e}"))?;
        }
        Ok(o)
    }

    /// Makes these the options of every robot read from now on in this process.
    ///
    /// # Errors
    /// As [`XacroCli::options`].
    pub fn apply(&self) -> anyhow::Result<()> {
        dh_workflows::xacro::set_default_options(self.options()?);
        Ok(())
    }
}
