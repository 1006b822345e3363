//! Measurement sets: joint values and measured target positions.
//!
//! Frames and units: joint values in radians (metres for prismatic joints); measured points in
//! the measuring device's own frame, metres; a measured orientation (6-DoF devices) is the
//! target frame's rotation in the device frame, its standard deviation in radians.

use std::sync::Arc;

pub use compact_str::CompactString;

use nalgebra::{UnitQuaternion, Vector3};

/// Smallest standard deviation a measurement may carry: 1e-9 (metres for a point's `sigma`,
/// radians for `sigma_rot`). A nanometre is below the noise of every measuring device, and
/// residuals over it keep the chi-square of the verdict finite (a sigma of 1e-300 made it
/// infinite, and an infinite statistic drew the verdict "model complete"). The readers refuse
/// a smaller non-zero value (0 is floored, see [`crate::csv::SIGMA_FLOOR`]).
pub const MIN_SIGMA: f64 = 1e-9;

/// Which part of the data a sample belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Used to fit parameters.
    Calibration,
    /// Held out to judge the fit.
    Validation,
}

/// One measured point.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// One value per entry of [`Measurements::joint_names`] (radians or metres). Shared, not
    /// copied, by the prepared sample ([`crate::model::Observed::q`]) when the model's rows
    /// are the set's columns in order (build it with `vec.into()`).
    pub q: Arc<[f64]>,
    /// Index into [`Measurements::targets`]: which reflector or marker was measured.
    pub target: usize,
    /// Measured position in the device frame (metres).
    pub point: Vector3<f64>,
    /// Per-axis standard deviation of `point` (metres), when known.
    pub sigma: Option<Vector3<f64>>,
    /// Pose identifier: samples with the same id repeat one pose (pure error). Names of up to
    /// 24 bytes are held in place, without an allocation of their own (millions of samples
    /// each carry one); build it with `name.into()`.
    pub config: Option<CompactString>,
    /// Calibration or validation.
    pub split: Split,
    /// 1-based line in the source file (0 when generated).
    pub line: usize,
    /// `Some` for a contact sample (see [`crate::socket`]): the target sat in this unknown
    /// fixed point, `point` is not a measurement and is ignored. Boxed: most samples have
    /// none, and millions of samples would carry its size.
    pub socket: Option<Box<Socket>>,
    /// Measurement session: index into [`Measurements::sessions`] (0 when the set has none).
    /// Samples of one session share one device frame `T_device_base`; the device (a laser
    /// tracker) was moved between sessions.
    pub session: usize,
    /// The measured orientation of the target's frame, for a 6-DoF device (a tracker's 6-DoF
    /// probe, an optical marker body); `None` for a point. Boxed as `socket`.
    pub orientation: Option<Box<Orientation>>,
    /// When the sample was measured (seconds, any origin: only differences are used), from the
    /// measurement file's `time` column; `None` when the set has no clock. What time effects
    /// (`thermal_growth`, [`crate::effects_order`]) read: the time since the set's first
    /// timed sample.
    pub time: Option<f64>,
}

/// A measured orientation: the rotation of the target's frame in the device frame, with the
/// standard deviation of each component of its rotation vector.
#[derive(Clone, Debug, PartialEq)]
pub struct Orientation {
    /// `R_device_target`.
    pub rotation: UnitQuaternion<f64>,
    /// Standard deviation per axis (radians), > 0.
    pub sigma: f64,
}

/// An unknown fixed point that a target was placed in (a ball in a socket): every sample naming
/// it puts the target at the same place, wherever that is.
#[derive(Clone, Debug, PartialEq)]
pub struct Socket {
    /// The point's name; samples with the same name touch the same point.
    pub name: String,
    /// Another socket at a known distance from this one (the scale of the set), when known.
    pub partner: Option<SocketDistance>,
}

/// A known distance between two sockets.
#[derive(Clone, Debug, PartialEq)]
pub struct SocketDistance {
    /// The other socket's name.
    pub socket: String,
    /// Centre-to-centre distance (metres).
    pub distance: f64,
    /// Its standard deviation (metres).
    pub sigma: f64,
}

/// A measurement set.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Measurements {
    /// Joint names, in the order of every sample's `q`.
    pub joint_names: Vec<String>,
    /// Target (reflector, marker) names; a set with one target has one entry.
    pub targets: Vec<String>,
    /// The samples, in file order.
    pub samples: Vec<Sample>,
    /// Measurement session names (the `session` column), in order of first appearance; empty
    /// when the set has no session column: every sample is then in one session, index 0.
    pub sessions: Vec<String>,
}

#[cfg(test)]
impl Sample {
    /// For tests: a calibration sample of target 0 at joint values `q`, measured at `point`
    /// (metres), from line `line`; no sigma, config, socket, session or orientation.
    pub(crate) fn test_point(q: &[f64], point: Vector3<f64>, line: usize) -> Self {
        Sample {
            q: q.into(),
            target: 0,
            point,
            sigma: None,
            config: None,
            split: Split::Calibration,
            line,
            socket: None,
            session: 0,
            orientation: None,
            time: None,
        }
    }
}

#[cfg(test)]
impl Measurements {
    /// For tests: `samples` of one target `t` on the UR5 of [`crate::test_robots::ur5`]
    /// (joints `j1`..`j6`), without sessions.
    pub(crate) fn test_ur5(samples: Vec<Sample>) -> Self {
        Measurements {
            joint_names: (1..=6).map(|j| format!("j{j}")).collect(),
            targets: vec!["t".into()],
            samples,
            sessions: vec![],
        }
    }
}

impl Measurements {
    /// The same set with only the samples `keep(index, sample)` accepts (names and targets
    /// kept, sample order kept).
    pub fn filtered(&self, keep: impl Fn(usize, &Sample) -> bool) -> Measurements {
        Measurements {
            joint_names: self.joint_names.clone(),
            targets: self.targets.clone(),
            sessions: self.sessions.clone(),
            samples: self
                .samples
                .iter()
                .enumerate()
                .filter(|(i, s)| keep(*i, s))
                .map(|(_, s)| s.clone())
                .collect(),
        }
    }

    /// Number of sessions (at least 1).
    pub fn session_count(&self) -> usize {
        self.sessions.len().max(1)
    }

    /// The name of session `s`: its entry of [`Measurements::sessions`], or `"1"`, `"2"`, …
    /// (1-based) when the set names none.
    pub fn session_name(&self, s: usize) -> String {
        self.sessions
            .get(s)
            .cloned()
            .unwrap_or_else(|| (s + 1).to_string())
    }
}
