//! The effect models themselves, as [`Effect`]s on the DH parameters: gear harmonics
//! ([`GearHarmonic`]), joint coupling ([`Coupling`]), a device length scale ([`Scale`]), the tilt
//! of parallel axes ([`ParallelTilt`]) and gravitational deflection ([`Gravitational`]). Their
//! parameters' units are in the module's label table.

use super::*;

/// Which harmonics of a joint's turn a [`GearHarmonic`] has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Harmonics {
    /// Once per turn.
    First,
    /// Twice per turn alone.
    Second,
    /// Once and twice per turn.
    Both,
}

impl Harmonics {
    /// The basis functions of `q` it uses (indices into `sin q, cos q, sin 2q, cos 2q`).
    pub(super) fn basis(self) -> std::ops::Range<usize> {
        match self {
            Self::First => 0..2,
            Self::Second => 2..4,
            Self::Both => 0..4,
        }
    }
}

/// Once and twice per revolution transmission errors: `theta_J += A sin q + B cos q`, named
/// `gear_harmonic:J`; `A2 sin 2q + B2 cos 2q` alone, named `gear_harmonic2:J`; both, named
/// `gear_harmonic:J:2` (radians; `q` the joint value).
#[derive(Clone, Debug, PartialEq)]
pub struct GearHarmonic {
    pub(super) joint: String,
    pub(super) row: usize,
    pub(super) harmonics: Harmonics,
}

impl Effect for GearHarmonic {
    fn parameter_names(&self) -> Vec<String> {
        let l = self.label();
        ["sin", "cos", "sin2", "cos2"][self.harmonics.basis()]
            .iter()
            .map(|s| format!("{l}.{s}"))
            .collect()
    }
    fn label(&self) -> String {
        match self.harmonics {
            Harmonics::First => format!("gear_harmonic:{}", self.joint),
            Harmonics::Second => format!("gear_harmonic2:{}", self.joint),
            Harmonics::Both => format!("gear_harmonic:{}:2", self.joint),
        }
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        EffectField::Theta
    }
    fn delta(&self, q: &[f64], params: &[f64]) -> f64 {
        let mut g = [0.0; 4];
        self.gradient(q, params, &mut g);
        g.iter().zip(params).map(|(a, b)| a * b).sum()
    }
    fn gradient(&self, q: &[f64], _params: &[f64], out: &mut [f64]) {
        let v = q.get(self.row).copied().unwrap_or(0.0);
        let basis = [v.sin(), v.cos(), (2.0 * v).sin(), (2.0 * v).cos()];
        for (o, b) in out.iter_mut().zip(&basis[self.harmonics.basis()]) {
            *o = *b;
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length; self.harmonics.basis().len()]
    }
    fn units(&self) -> Vec<String> {
        vec!["rad".into(); self.harmonics.basis().len()]
    }
}

/// `theta_J += k · q_K`, named `coupling:J:K`.
#[derive(Clone, Debug, PartialEq)]
pub struct Coupling {
    pub(super) joint: String,
    pub(super) driver: String,
    pub(super) row: usize,
    pub(super) driver_row: usize,
}

impl Effect for Coupling {
    fn parameter_names(&self) -> Vec<String> {
        vec![format!("coupling:{}:{}", self.joint, self.driver)]
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        EffectField::Theta
    }
    fn delta(&self, q: &[f64], params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0) * q.get(self.driver_row).copied().unwrap_or(0.0)
    }
    fn gradient(&self, q: &[f64], _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = q.get(self.driver_row).copied().unwrap_or(0.0);
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length]
    }
    fn units(&self) -> Vec<String> {
        vec!["rad/rad".into()]
    }
}

/// The measuring device's length scale, named `scale`: modelled positions `× (1 + s)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale;

impl Effect for Scale {
    fn parameter_names(&self) -> Vec<String> {
        vec!["scale".into()]
    }
    fn joint(&self) -> &str {
        ""
    }
    fn field(&self) -> EffectField {
        EffectField::Scale
    }
    fn delta(&self, _q: &[f64], params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0)
    }
    fn gradient(&self, _q: &[f64], _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = 1.0;
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length]
    }
    fn units(&self) -> Vec<String> {
        vec!["1".into()]
    }
}

/// The tilt about `y` of a near-parallel pair ending at joint `J`, named `parallel_tilt:J`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParallelTilt {
    /// The later joint of the pair (the label's).
    pub(super) later: String,
    /// The row that carries the tilt (the effect's joint).
    pub(super) joint: String,
}

impl Effect for ParallelTilt {
    fn parameter_names(&self) -> Vec<String> {
        vec![format!("parallel_tilt:{}", self.later)]
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        EffectField::Beta
    }
    fn delta(&self, _q: &[f64], params: &[f64]) -> f64 {
        params.first().copied().unwrap_or(0.0)
    }
    fn gradient(&self, _q: &[f64], _params: &[f64], out: &mut [f64]) {
        if let Some(o) = out.first_mut() {
            *o = 1.0;
        }
    }
    fn scales(&self, length: f64) -> Vec<f64> {
        vec![length]
    }
    fn units(&self) -> Vec<String> {
        vec!["rad".into()]
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum GravityKind {
    Compliance,
    Lateral,
    Backlash,
}

/// Effects driven by the gravity torque: `compliance:J`, `lateral_compliance:J`,
/// `backlash:J` (see the module docs).
#[derive(Clone, Debug)]
pub struct Gravitational {
    pub(super) kind: GravityKind,
    pub(super) joint: String,
    pub(super) row: usize,
    pub(super) prismatic: bool,
    pub(super) gravity: Arc<GravityModel>,
}

impl Gravitational {
    pub(super) fn axis(&self) -> TorqueAxis {
        if self.kind == GravityKind::Lateral {
            TorqueAxis::Lateral
        } else {
            TorqueAxis::Joint
        }
    }

    pub(super) fn basis(&self, q: &[f64]) -> f64 {
        let tau = self.gravity.torque(q, self.row, self.axis());
        match self.kind {
            GravityKind::Backlash => {
                let t0 = 0.05 * self.gravity.torque_scale(self.row, TorqueAxis::Joint);
                (tau / t0).tanh()
            }
            _ => tau,
        }
    }
}

impl Effect for Gravitational {
    fn parameter_names(&self) -> Vec<String> {
        vec![self.label()]
    }
    fn label(&self) -> String {
        let k = match self.kind {
            GravityKind::Compliance => "compliance",
            GravityKind::Lateral => "lateral_compliance",
            GravityKind::Backlash => "backlash",
        };
        format!("{k}:{}", self.joint)
    }
    fn joint(&self) -> &str {
        &self.joint
    }
    fn field(&self) -> EffectField {
        match (self.kind, self.prismatic) {
            (GravityKind::Lateral, _) => EffectField::Alpha,
            (_, true) => EffectField::D,
            _ => EffectField::Theta,
        }
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
    fn scales(&self, length: f64) -> Vec<f64> {
        // A unit of the scaled parameter moves the joint as much as a unit of an angle or
        // length column does: the compliance times a typical torque.
        let motion = if self.prismatic { 1.0 } else { length };
        match self.kind {
            GravityKind::Backlash => vec![length],
            _ => vec![motion / self.gravity.torque_scale(self.row, self.axis())],
        }
    }
    fn units(&self) -> Vec<String> {
        vec![match (self.kind, self.prismatic) {
            (GravityKind::Backlash, _) => "rad".into(),
            (GravityKind::Compliance, true) => "m/N".into(),
            _ => "rad/(N m)".into(),
        }]
    }
}
