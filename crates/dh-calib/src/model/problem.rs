//! A model with its observations as a [`Problem`] for [`crate::fit::solve`]: all samples
//! ([`ModelProblem`]) or some by index ([`SubsetProblem`]); 3 residuals per point, 6 per pose.

use super::{Model, Observed};
use crate::fit::Problem;

/// A model with observations: the [`Problem`] that [`crate::fit::solve`] minimises.
#[derive(Clone, Copy, Debug)]
pub struct ModelProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// The samples.
    pub observations: &'a [Observed],
}

/// A model with samples reachable by block: [`ModelProblem`] (all of them) and
/// [`SubsetProblem`] (some, by index) share one [`Problem`] implementation through it.
trait Samples: Sync {
    fn model(&self) -> &Model;
    fn count(&self) -> usize;
    fn sample(&self, block: usize) -> Option<&Observed>;
}

impl Samples for ModelProblem<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn count(&self) -> usize {
        self.observations.len()
    }
    fn sample(&self, block: usize) -> Option<&Observed> {
        self.observations.get(block)
    }
}

impl<S: Samples> Problem for S {
    fn parameter_count(&self) -> usize {
        self.model().parameter_count()
    }
    fn block_count(&self) -> usize {
        self.count()
    }
    fn block_size(&self, block: usize) -> usize {
        self.sample(block)
            .map_or(3, |o| o.observation.residual_count())
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        if let Some(o) = self.sample(block) {
            self.model().residuals(x, o, out);
        }
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        if let Some(o) = self.sample(block) {
            self.model().jacobian(x, o, columns, residuals, jacobian);
        }
    }
}

/// Some of a model's observations, by index (a cross-validation fold's training samples): the
/// [`Problem`] of [`ModelProblem`] over `observations[i]` for `i` in `subset`, without copies.
#[derive(Clone, Copy, Debug)]
pub struct SubsetProblem<'a> {
    /// The model.
    pub model: &'a Model,
    /// All samples.
    pub observations: &'a [Observed],
    /// Indices into `observations` of the samples in the problem, one block each.
    pub subset: &'a [usize],
}

impl Samples for SubsetProblem<'_> {
    fn model(&self) -> &Model {
        self.model
    }
    fn count(&self) -> usize {
        self.subset.len()
    }
    fn sample(&self, block: usize) -> Option<&Observed> {
        self.subset
            .get(block)
            .and_then(|&i| self.observations.get(i))
    }
}
