//! Errors the CLI reports with a hint, and the exit-code contract.

use dh_sheet::SheetError;
use urdf_axes::UrdfError;

pub use dh_sheet::error::{hinted, Hinted};

/// The `hint:` line for an error: a [`Hinted`] one's own, a [`SheetError`]'s own, else one for
/// the library errors whose remedy is a command-line option or a tool (the libraries know no
/// options).
pub fn hint_for(e: &anyhow::Error) -> Option<String> {
    if let Some(h) = e.chain().find_map(|c| c.downcast_ref::<Hinted>()) {
        return Some(h.hint.clone());
    }
    if let Some(h) = e
        .chain()
        .find_map(|c| c.downcast_ref::<SheetError>().and_then(SheetError::hint))
    {
        return Some(h);
    }
    let u = e.chain().find_map(|c| c.downcast_ref::<UrdfError>())?;
    Some(match u {
        UrdfError::SeveralLeaves { leaves, .. } => format!(
            "choose the tip with --tip, e.g. --tip {}",
            leaves.first().map_or("LINK", String::as_str)
        ),
        UrdfError::UnknownLink { role, .. } => {
            format!("--{role} takes the name of a <link> of the URDF (not of a joint)")
        }
        UrdfError::Disconnected {
            reversed: false,
            base,
            ..
        } => format!(
            "the tip must lie in the link tree below the base; '{base}' is not above it \
             (leave out --base to start at the root link)"
        ),
        UrdfError::JointTypeInChain { joint, .. } => format!(
            "a floating or planar joint has no axis line: start the chain below '{joint}' \
             with --base (its child link), or end it above with --tip"
        ),
        UrdfError::NoMovingJoint { .. } => "choose a --base and --tip with a revolute, \
             continuous or prismatic joint between them"
            .into(),
        UrdfError::EntityDeclaration { .. } => {
            "expand the entities first (xacro, or by hand): urdf-dh reads plain URDF".into()
        }
        UrdfError::TooLarge { .. } => "a robot description is a few megabytes at most (meshes live \
             in their own files): check what is being read"
            .into(),
        UrdfError::NotUtf8 { .. } => {
            "convert the file to UTF-8, e.g. iconv -f latin1 -t utf-8 FILE > FILE.utf8".into()
        }
        UrdfError::SeveralRoots { .. } => {
            "join every link to one tree with a joint (a fixed one will do), or remove the stray links"
                .into()
        }
        UrdfError::Cycle { .. } | UrdfError::NoRoot { .. } => {
            "a URDF is a tree of links: remove one joint of the cycle".into()
        }
        _ => return None,
    })
}

/// What a successful run found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0: verified, matched.
    Pass,
    /// Exit 1: a check or verification found a difference.
    Differs,
}
