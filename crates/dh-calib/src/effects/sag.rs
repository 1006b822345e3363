//! A cantilever sagging under its own weight: `gravity_sag:J`, the tip moving along gravity
//! with the cube of its lever arm about joint `J` (issue 33 §5).
//!
//! # Model
//! In the robot's base link frame (metres), with `ĝ` the unit gravity direction (`--gravity`,
//! else `-z` of the base link, the same as [`crate::gravity`]), the tip and every target move
//! by
//!
//! ```text
//! Δp = c · |l_J(q)|³ · ĝ,     l_J(q) = z_J · ((p − o_J) × ĝ)
//! ```
//!
//! `o_J`, `z_J` a point of joint `J`'s axis and its unit direction, `p` the tip's origin (the
//! table's tool applied: the targets sit within centimetres of it, and a sag differs between
//! them by a fraction of that), all at the **nominal** geometry in the base link frame
//! ([`GravityModel::lever`]: the torque of a weight of 1 N at the tip, in N m per N). `c`
//! (1/m²) is the sag at a lever arm of 1 m, in metres: positive moves the tip down. A beam of
//! length `l` clamped at one end and loaded at the other deflects by `F l³ / (3 E I)` (S. P.
//! Timoshenko, J. M. Gere, *Mechanics of Materials*, 1972, §9.5); a link held at a joint under
//! the weight it carries bends so, its lever arm about a horizontal axis standing for its
//! length. `|l|` because the deflection is along gravity on either side of the axis.
//!
//! The geometry is the nominal one, as the gravity torques' ([`crate::effects`]' module
//! docs): a 1 mm error of a 1 m arm changes a 0.3 mm sag by 1 µm, and the effect stays linear
//! in `c`. A joint whose axis is parallel to gravity (or runs through the tip) has no lever arm:
//! the label is refused for it ([`MIN_SAG_LEVER`]), and automatic diagnosis proposes it for
//! the other revolute joints of a serial robot (with link inertials, as a rival of the
//! compliances, decided by the held-out RMS: see `crate::rivals`).

use super::*;

use crate::effect_label::bad_label;
use crate::gravity::Inertials;
use dh_core::JointSampler;

/// A joint whose gravity lever arm has an RMS over the workspace below this fraction of the
/// arm's size takes no `gravity_sag` (its axis is parallel to gravity, or runs through the
/// tip): the same bound as the verdict's lever structure test.
pub const MIN_SAG_LEVER: f64 = 0.05;

/// Joint values drawn (fixed seed, within the limits) for a lever arm's typical size.
const LEVER_SAMPLES: usize = 32;

/// `gravity_sag:J` (see the module docs).
#[derive(Clone, Debug)]
pub struct GravitySag {
    joint: String,
    row: usize,
    /// The nominal geometry and gravity (masses, if any, are not used).
    gravity: Arc<GravityModel>,
    /// `ĝ`, the unit gravity direction in the base link frame.
    down: nalgebra::Vector3<f64>,
    /// RMS of `|l|³` over the workspace (m³): the column scale.
    typical: f64,
}

impl GravitySag {
    /// The sag of the lever arm about row `row` (named `joint`) of `ctx`'s robot: with
    /// `ctx.gravity`'s geometry and gravity when it has inertials, else the tree's nominal
    /// geometry under `ctx.gravity_vector`.
    ///
    /// # Errors
    /// [`CalibError::BadOption`] for a tree with branches, a zero or non-finite gravity vector,
    /// or a joint whose lever arm stays below [`MIN_SAG_LEVER`] of the arm's size.
    pub(super) fn new(
        label: &str,
        ctx: &EffectContext,
        joint: &str,
        row: usize,
    ) -> Result<Self, CalibError> {
        if !ctx.tree.branches().is_empty() {
            return Err(bad_label(
                label,
                "expected a serial robot, found a tree (its branches carry their own tips)",
            ));
        }
        let gravity = match &ctx.gravity {
            Some(g) => g.clone(),
            None => Arc::new(GravityModel::new(
                &ctx.tree,
                &Inertials::default(),
                ctx.gravity_vector,
            )?),
        };
        let g = gravity.gravity();
        let norm = g.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(bad_label(
                label,
                format!("expected a non-zero gravity vector, found {g:?} m/s²"),
            ));
        }
        let tree = gravity.tree();
        let mut sampler = JointSampler::new(tree.rows(), tree.size(), 0x5a6);
        let mut q = Vec::new();
        let (mut l2, mut l6) = (0.0, 0.0);
        for _ in 0..LEVER_SAMPLES {
            sampler.next_into(&mut q);
            let l = gravity.lever(&q, row);
            l2 += l * l;
            l6 += l.powi(6);
        }
        let rms = (l2 / LEVER_SAMPLES as f64).sqrt();
        let size = tree.size();
        if rms < MIN_SAG_LEVER * size {
            return Err(bad_label(
                label,
                format!(
                    "expected a joint whose axis is not parallel to gravity, found '{joint}' \
                     (its gravity lever arm is {rms:.3} m RMS over the workspace, below {} % \
                     of the arm's size {size:.3} m)",
                    MIN_SAG_LEVER * 100.0
                ),
            ));
        }
        Ok(Self {
            joint: joint.into(),
            row,
            down: g / norm,
            typical: (l6 / LEVER_SAMPLES as f64).sqrt(),
            gravity,
        })
    }

    /// `|l_J(q)|³` (m³).
    fn basis(&self, q: &[f64]) -> f64 {
        self.gravity.lever(q, self.row).abs().powi(3)
    }
}

impl Effect for GravitySag {
    fn parameter_names(&self) -> Vec<String> {
        vec![self.label()]
    }
    fn label(&self) -> String {
        format!("gravity_sag:{}", self.joint)
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        EffectField::Shift
    }
    fn shift_direction(&self) -> nalgebra::Vector3<f64> {
        self.down
    }
    fn delta(&self, q: &[f64], params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0) * self.basis(q)
    }
    fn gradient(&self, q: &[f64], _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = self.basis(q);
        }
    }
    fn gravity_model(&self) -> Option<&Arc<GravityModel>> {
        Some(&self.gravity)
    }
    fn scales(&self, _length: f64) -> Vec<f64> {
        vec![self.typical.max(f64::MIN_POSITIVE)]
    }
    fn units(&self) -> Vec<String> {
        vec!["1/m^2".into()]
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::fit::{numeric_jacobian, Problem};
    use crate::model::{Model, ModelOptions, ModelProblem, Observation, Observed};
    use crate::test_robots::ur5;

    fn context(gravity: Vector3<f64>) -> EffectContext {
        EffectContext {
            gravity_vector: gravity,
            ..EffectContext::serial(&ur5())
        }
    }

    /// A UR5 with `gravity_sag:j2` at a sag of 5 cm at 1 m (large, so that a wrong Jacobian
    /// shows), a second session, a target and random parameters.
    fn model(gravity: Vector3<f64>) -> (Model, Vec<f64>, Arc<dyn Effect>) {
        let t = ur5();
        let sag = parse_label_in("gravity_sag:j2", &context(gravity)).unwrap();
        let mut m = Model::new(&t, &["a".into()], &ModelOptions::default()).unwrap();
        m.set_device(&Isometry3::from_parts(
            Translation3::new(1.5, -0.7, 0.4),
            UnitQuaternion::from_euler_angles(0.4, -0.9, 2.2),
        ));
        m.set_target(0, Vector3::new(0.05, -0.02, 0.1));
        m.add_session(1, "moved", &Isometry3::translation(0.5, -0.2, 0.1));
        let range = m.add_effect(sag.clone()).unwrap();
        let mut x: Vec<f64> = (0..m.parameter_count())
            .map(|i| 3e-3 * ((i as f64 * 0.7).sin() + 0.1))
            .collect();
        x[range.start] = 0.05;
        (m, x, sag)
    }

    #[test]
    fn the_tip_moves_along_gravity_by_c_times_the_lever_cubed() {
        let g = Vector3::new(-9.81, 0.0, 0.0);
        let (m, mut x, sag) = model(g);
        let c = m.index_of("gravity_sag:j2").unwrap();
        let q = [0.3, -1.2, 0.8, 0.1, 1.5, -0.4];
        let with = m.robot_fk(&x, &q);
        let sagged = x[c];
        x[c] = 0.0;
        let without = m.robot_fk(&x, &q);
        // The lever arm by hand at the nominal geometry: z_2 · ((p − o_2) × ĝ).
        let t = ur5();
        let frames = t.frames(&q).unwrap();
        let tip = frames[6] * t.tool;
        let z = frames[1].rotation * Vector3::z();
        let l =
            z.dot(&(tip.translation.vector - frames[1].translation.vector).cross(&-Vector3::x()));
        let want = -Vector3::x() * sagged * l.abs().powi(3);
        assert!(l.abs() > 0.1, "{l}");
        assert!((with.translation.vector - without.translation.vector - want).norm() < 1e-12);
        assert!(with.rotation.angle_to(&without.rotation) < 1e-12);
        assert_eq!(sag.units(), ["1/m^2"]);
    }

    #[test]
    fn the_analytic_jacobian_of_a_sag_matches_central_differences() {
        let (m, x, _) = model(Vector3::new(0.0, 0.0, -9.81));
        assert_jacobian(&m, &x, false);
    }

    /// With a robot growth beside it, the sag grows with the robot (the shift is in the base
    /// link frame, the growth about its origin): both Jacobians still match.
    #[test]
    fn a_sag_beside_a_thermal_growth_has_the_analytic_jacobian() {
        let (mut m, mut x, _) = model(Vector3::new(0.0, 0.0, -9.81));
        let growth =
            parse_label_in("thermal_growth", &context(Vector3::new(0.0, 0.0, -9.81))).unwrap();
        let range = m.add_effect(growth).unwrap();
        // k = 1 %, ln tau = 0 (tau = 1 s, at times 0 to 2 s: well inside its curve).
        x.resize(m.parameter_count(), 0.0);
        x[range.start] = 0.01;
        x[range.start + 1] = 0.0;
        assert_jacobian(&m, &x, true);
    }

    /// Checks `m`'s analytic Jacobian at `x` against central differences on points and poses of
    /// two sessions; `timed`: each sample at its own time (0.4 s apart).
    fn assert_jacobian(m: &Model, x: &[f64], timed: bool) {
        let t = ur5();
        let mut sampler = JointSampler::new(&t.rows, t.size(), 5);
        let mut q = Vec::new();
        let mut obs = Vec::new();
        let context_at = |i: usize| crate::model::SampleContext {
            time: timed.then_some(i as f64 * 0.4),
            ..Default::default()
        };
        for i in 0..6 {
            sampler.next_into(&mut q);
            let session = i % 2;
            obs.push(Observed {
                session,
                q: q.as_slice().into(),
                observation: Observation::Point {
                    target: 0,
                    point: m.point(x, &q, 0) + Vector3::new(1e-3, -2e-3, 5e-4),
                },
                context: context_at(i),
            });
            obs.push(Observed {
                session,
                q: q.as_slice().into(),
                observation: Observation::Pose(Box::new(m.tip(x, &q))),
                context: context_at(i),
            });
        }
        let p = ModelProblem {
            model: m,
            observations: &obs,
        };
        let cols: Vec<usize> = (0..m.parameter_count()).collect();
        let steps = vec![1e-6; cols.len()];
        for b in 0..p.block_count() {
            let rows = p.block_size(b);
            let mut r = vec![0.0; rows];
            let mut j = vec![0.0; rows * cols.len()];
            p.jacobian(x, b, &cols, &mut r, &mut j);
            let num = numeric_jacobian(&p, x, b, &cols, &steps);
            for i in 0..rows {
                for (k, c) in cols.iter().enumerate() {
                    let d = (j[i * cols.len() + k] - num[(i, k)]).abs();
                    assert!(
                        d < 1e-7,
                        "block {b} row {i} {}: analytic {} numeric {}",
                        m.parameters()[*c].name,
                        j[i * cols.len() + k],
                        num[(i, k)]
                    );
                }
            }
        }
    }

    #[test]
    fn a_joint_along_gravity_has_no_sag() {
        let down = context(Vector3::new(0.0, 0.0, -9.81));
        let e = parse_label_in("gravity_sag:j1", &down)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expected a joint whose axis is not parallel to gravity, found 'j1'"),
            "{e}"
        );
        // On a wall (gravity along x), the first joint's axis is horizontal.
        let wall = context(Vector3::new(-9.81, 0.0, 0.0));
        assert!(parse_label_in("gravity_sag:j1", &wall).is_ok());
        let none = context(Vector3::zeros());
        let e = parse_label_in("gravity_sag:j2", &none)
            .unwrap_err()
            .to_string();
        assert!(e.contains("expected a non-zero gravity vector"), "{e}");
        let labels: Vec<String> = candidates(&down, &[])
            .effects
            .iter()
            .map(|e| e.label())
            .filter(|l| l.starts_with("gravity_sag"))
            .collect();
        // j5 and j6 turn within a flange's length of the tip: no lever arm worth a candidate.
        assert_eq!(
            labels,
            ["gravity_sag:j2", "gravity_sag:j3", "gravity_sag:j4"]
        );
    }
}
