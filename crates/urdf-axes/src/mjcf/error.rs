//! Errors of reading an MJCF document: each names the element, its file (when it came through
//! an `<include>`) and its 1-based line.

use std::fmt;

use thiserror::Error;

use crate::UrdfError;

/// Where an element of an MJCF document is: its description (`joint 'j1'`, `<body>`), the
/// included file it came from (`None` for the main document) and its 1-based line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Place {
    /// The element: `tag 'name'` when it has a name, `<tag>` otherwise.
    pub element: String,
    /// The included file holding it, as its `<include file>` names it; `None` for the main
    /// document.
    pub file: Option<String>,
    /// 1-based line of the element's start tag.
    pub line: usize,
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.file {
            Some(file) => write!(f, "{} ({file}, line {})", self.element, self.line),
            None => write!(f, "{} (line {})", self.element, self.line),
        }
    }
}

/// Everything that can be wrong with an MJCF document (MuJoCo XML) read as a robot model.
///
/// Messages are lowercase, say "expected X, found Y" and name the element and its line.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MjcfError {
    /// Text that is not well-formed XML, or a root other than `<mujoco>`.
    #[error("mjcf parse error{}{}: {message}", .file.as_ref().map(|f| format!(" in {f}")).unwrap_or_default(), .line.map(|l| format!(" (line {l})")).unwrap_or_default())]
    Xml {
        /// The included file, `None` for the main document.
        file: Option<String>,
        /// 1-based line, when known.
        line: Option<usize>,
        /// What was expected and what was found.
        message: String,
    },
    /// An element whose content changes the kinematics is malformed, refers to something
    /// undefined, or is a construct the reader does not take.
    #[error("{at}: {message}")]
    Invalid {
        /// The element.
        at: Place,
        /// What was expected and what was found.
        message: String,
    },
    /// The model, converted, is not one tree of uniquely named bodies and joints (or another
    /// fault of the model's own validation).
    #[error(transparent)]
    Model(#[from] UrdfError),
}

impl MjcfError {
    /// An [`MjcfError::Invalid`] at `at`.
    pub(crate) fn at(at: Place, message: impl Into<String>) -> MjcfError {
        MjcfError::Invalid {
            at,
            message: message.into(),
        }
    }
}
