//! The position residuals of a session's calibration samples at one point, computed once for
//! every pass that reads them there ([`ResidualsAt`]), and the session's fit problem whose
//! sum of squares comes from them ([`SessionProblem`]).
//!
//! At the geometric fit of a calibration without effects, four passes over every sample read
//! the same residuals: the fit's last sum of squares, the step's distances, the outlier
//! screen's first round and the final checks. On 2 000 000 samples each pass is about half a
//! second on two cores.

use std::sync::Mutex;

use super::*;

/// The position residuals (model minus measured, device frame, metres) of the calibration
/// samples at the last point asked for, keyed by the model's revision and the point's bits.
#[derive(Default)]
pub(crate) struct ResidualsAt(Mutex<Option<Kept>>);

struct Kept {
    revision: u64,
    x: Vec<u64>,
    residuals: Arc<Vec<Vector3<f64>>>,
}

impl ResidualsAt {
    /// The position residuals of `obs` (the session's calibration samples, always the same
    /// list) under `model` at `x`: kept from the last call when the model and `x` are the
    /// same, else computed ([`residual_vectors`], the same values) and kept instead.
    pub(crate) fn of(&self, model: &Model, x: &[f64], obs: &[Observed]) -> Arc<Vec<Vector3<f64>>> {
        let bits: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
        let revision = model.revision();
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(k) = kept.as_ref() {
            if k.revision == revision && k.x == bits {
                return k.residuals.clone();
            }
        }
        // The old residuals freed before the new ones are made.
        *kept = None;
        let residuals = Arc::new(residual_vectors(model, x, obs));
        *kept = Some(Kept {
            revision,
            x: bits,
            residuals: residuals.clone(),
        });
        residuals
    }
}

/// The session's model over all its calibration samples, as [`ModelProblem`], with the sum of
/// squares of a sample set of points summed from [`ResidualsAt`]: the same number, summed in the
/// same order as [`fit::sum_of_squares`], whose residuals the passes after the fit then read.
pub(crate) struct SessionProblem<'s, 'a> {
    pub(crate) session: &'s Session<'a>,
}

impl SessionProblem<'_, '_> {
    fn inner(&self) -> ModelProblem<'_> {
        ModelProblem {
            model: &self.session.model,
            observations: &self.session.prep.cal,
        }
    }
}

impl fit::Problem for SessionProblem<'_, '_> {
    fn parameter_count(&self) -> usize {
        self.inner().parameter_count()
    }
    fn block_count(&self) -> usize {
        self.inner().block_count()
    }
    fn block_size(&self, block: usize) -> usize {
        self.inner().block_size(block)
    }
    fn residuals(&self, x: &[f64], block: usize, out: &mut [f64]) {
        self.inner().residuals(x, block, out);
    }
    fn jacobian(
        &self,
        x: &[f64],
        block: usize,
        columns: &[usize],
        residuals: &mut [f64],
        jacobian: &mut [f64],
    ) {
        self.inner()
            .jacobian(x, block, columns, residuals, jacobian);
    }
    fn sum_of_squares(&self, x: &[f64]) -> Option<f64> {
        let cal = &self.session.prep.cal;
        let points = cal
            .iter()
            .all(|o| matches!(o.observation, Observation::Point { .. }));
        if !points {
            return fit::sum_of_squares(&self.inner(), x);
        }
        let residuals = self.session.position_residuals(x);
        // As `fit::sum_of_squares`: each block's squares in order, by segments of
        // `SEGMENT_BLOCKS` blocks beyond one segment, the segments' sums added in order.
        let segment = |rs: &[Vector3<f64>]| {
            let mut ssr = 0.0;
            for r in rs {
                for v in r.iter() {
                    ssr += v * v;
                }
            }
            ssr
        };
        let ssr: f64 = if residuals.len() <= fit::SEGMENT_BLOCKS {
            segment(&residuals)
        } else {
            residuals.chunks(fit::SEGMENT_BLOCKS).map(segment).sum()
        };
        ssr.is_finite().then_some(ssr)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::{simulate, SimulationOptions};

    /// The session's sum of squares is `fit::sum_of_squares`' bit for bit, on one segment and on
    /// several; the residuals are made once per point and model, and again when either changes.
    #[test]
    fn the_kept_residuals_give_the_sum_of_squares_and_follow_the_point() {
        let table = crate::test_robots::ur5();
        let options = CalibrationOptions::default();
        for poses in [120, fit::SEGMENT_BLOCKS + 500] {
            let (data, _) = simulate(
                &table,
                &SimulationOptions {
                    poses,
                    sigma: 2e-5,
                    ..SimulationOptions::default()
                },
            )
            .expect("a simulated set");
            let tree = DhTree::serial(&table);
            let mut session = Session::new(&tree, &data, &options, &[], None).expect("a session");
            let mut x = vec![0.0; session.model.parameter_count()];
            for (k, v) in x.iter_mut().enumerate() {
                *v = 1e-4 * (k as f64).sin();
            }
            let plain = ModelProblem {
                model: &session.model,
                observations: &session.prep.cal,
            };
            let problem = SessionProblem { session: &session };
            use fit::Problem;
            let expected = fit::sum_of_squares(&plain, &x).expect("finite");
            assert_eq!(problem.sum_of_squares(&x), Some(expected), "{poses} poses");
            let kept = session.position_residuals(&x);
            assert!(Arc::ptr_eq(&kept, &session.position_residuals(&x)));
            assert_eq!(
                *kept,
                residual_vectors(&session.model, &x, &session.prep.cal)
            );
            let mut y = x.clone();
            y[0] += 1e-6;
            assert!(!Arc::ptr_eq(&kept, &session.position_residuals(&y)));
            let again = session.position_residuals(&x);
            assert!(!Arc::ptr_eq(&kept, &again) && again == kept);
            session
                .model
                .set_device(&Isometry3::translation(1e-3, 0.0, 0.0));
            let moved = session.position_residuals(&x);
            assert!(moved != again);
        }
    }
}
