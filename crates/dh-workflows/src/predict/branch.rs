//! Choosing a branch of a calibrated tree (`--branch`): whose tool is predicted or
//! compensated, and which targets a prediction names by default. A serial robot has one chain
//! and nothing to choose.

use anyhow::Result;

use crate::calibrated::CalibratedModel;
use crate::error::hinted;
use crate::text::escape;

impl CalibratedModel {
    /// Whether the model is a tree with branches (a tree sheet's calibration).
    pub fn is_tree(&self) -> bool {
        !self.calibrated.tree().branches().is_empty()
    }

    /// The branches' names, quoted, for messages.
    pub fn branch_list(&self) -> String {
        self.calibrated
            .tree()
            .branches()
            .iter()
            .map(|b| format!("'{}'", escape(&b.name)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The name of branch `b`.
    pub fn branch_name(&self, b: usize) -> &str {
        self.calibrated
            .tree()
            .branches()
            .get(b)
            .map_or("", |br| br.name.as_str())
    }

    /// Chooses the branch `name` of a tree (read from the file shown as `origin`) for what
    /// follows: its tool is the one predicted and compensated, and a prediction without
    /// targets names its targets.
    ///
    /// # Errors
    /// A model without branches; a name that is none of them, naming those there are.
    pub fn choose_branch(&mut self, name: &str, origin: &str) -> Result<()> {
        if !self.is_tree() {
            return Err(hinted(
                format!(
                    "--branch '{}': {origin} is a serial model with one chain, not a tree",
                    escape(name)
                ),
                "drop --branch: it chooses a branch of a calibrated tree sheet",
            ));
        }
        match self.calibrated.tree().branch_index(name) {
            Some(b) => {
                self.branch = Some(b);
                Ok(())
            }
            None => Err(hinted(
                format!(
                    "--branch '{}': {origin} has no branch of that name; expected one of {}",
                    escape(name),
                    self.branch_list()
                ),
                "the branches are the tree sheet's `branches`, by name",
            )),
        }
    }

    /// The chain whose tool `what` (`predict --targets tool`, `compensate`) uses: the chosen
    /// branch, a tree's only branch, or a serial robot's one chain (0).
    ///
    /// # Errors
    /// A tree of several branches and none chosen, naming them.
    pub fn tool_chain(&self, what: &str, origin: &str) -> Result<usize> {
        if let Some(b) = self.branch {
            return Ok(b);
        }
        if self.calibrated.tree().branches().len() <= 1 {
            return Ok(0);
        }
        Err(hinted(
            format!(
                "{what}: {origin} is a tree with branches {}; expected --branch NAME to say whose tool",
                self.branch_list()
            ),
            "each branch has its own tool: choose one with --branch (the trunk's joints move every branch)",
        ))
    }
}
