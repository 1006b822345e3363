//! The findings of a calibration beyond the fit, as plain documents (metres, radians): the
//! outliers it named ([`OutliersDoc`]), the verdict on the final model ([`VerdictDoc`]) and the
//! rounds of the effect diagnosis ([`DiagnosisDoc`]).

use serde::{Deserialize, Serialize};

use super::doc::CandidateDoc;
use crate::calibrate::Report;
use crate::findings::{Diagnosis, NoiseTest, ResidualTest, StructureCheck, Verdict};
use crate::outliers::{Judged, OutlierReport, ScaleSource};

/// One flagged point (JSON `outliers.points`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutlierDoc {
    /// 1-based line of the sample in the data file (0 when generated).
    pub line: usize,
    /// The sample's pose identifier.
    pub config: Option<String>,
    /// Target name.
    pub target: String,
    /// `calibration` or `validation`.
    pub split: String,
    /// 3-D residual at the fit without the outliers (metres).
    pub residual: f64,
    /// The same over the per-axis scale.
    pub sigmas: f64,
}

/// The outlier screen (JSON `outliers`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutliersDoc {
    /// Family-wise level of the test (Bonferroni over the points).
    pub level: f64,
    /// Per-axis scale (metres).
    pub scale: f64,
    /// `known` (the given or the samples' sigma) or `robust` (median of the residuals).
    pub scale_source: String,
    /// Threshold for calibration points, in units of the scale.
    pub threshold: f64,
    /// `true` when they stayed in the fit (`--keep-outliers`).
    pub kept: bool,
    /// RMS of the screen's fit with them (metres).
    pub rms_with: f64,
    /// RMS of the screen's fit without them (metres).
    pub rms_without: f64,
    /// The effects the screen's model had besides the geometry (empty: geometric only).
    #[serde(default)]
    pub effects: Vec<String>,
    /// Fit-and-flag rounds.
    pub rounds: usize,
    /// Whether the flagged set settled.
    pub converged: bool,
    /// The flagged points, in file order.
    pub points: Vec<OutlierDoc>,
    /// The points a first judgement left out and a later one gave back (against a model with
    /// effects), in file order: in the fit or the held-out figures.
    #[serde(default)]
    pub given_back: Vec<GivenBackDoc>,
}

/// How far off a point was against one model (JSON `outliers.given_back[].before`, `after`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JudgedDoc {
    /// 3-D residual (metres).
    pub residual: f64,
    /// The same over the per-axis scale.
    pub sigmas: f64,
    /// That judgement's threshold for the point's split, in units of the scale.
    pub threshold: f64,
    /// The model's effects besides the geometry (empty: geometric only).
    pub effects: Vec<String>,
}

impl From<&Judged> for JudgedDoc {
    fn from(j: &Judged) -> Self {
        JudgedDoc {
            residual: j.residual,
            sigmas: j.sigmas,
            threshold: j.threshold,
            effects: j.effects.clone(),
        }
    }
}

/// One point given back (JSON `outliers.given_back`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GivenBackDoc {
    /// 1-based line of the sample in the data file (0 when generated).
    pub line: usize,
    /// The sample's pose identifier.
    pub config: Option<String>,
    /// Target name.
    pub target: String,
    /// `calibration` or `validation`.
    pub split: String,
    /// Against the model that first left it out.
    pub before: JudgedDoc,
    /// Against the final model.
    pub after: JudgedDoc,
    /// Why, in words: `5.2 sigma against the geometric model, 1.1 sigma against the geometry
    /// and backlash_direction:j2`.
    pub reason: String,
}

fn split_name(validation: bool) -> String {
    if validation {
        "validation".into()
    } else {
        "calibration".into()
    }
}

impl From<&OutlierReport> for OutliersDoc {
    fn from(r: &OutlierReport) -> Self {
        OutliersDoc {
            level: r.level,
            scale: r.scale,
            scale_source: match r.source {
                ScaleSource::Known => "known".into(),
                ScaleSource::Robust => "robust".into(),
            },
            threshold: r.threshold,
            kept: r.kept,
            rms_with: r.rms_with,
            rms_without: r.rms_without,
            effects: r.effects.clone(),
            rounds: r.rounds,
            converged: r.converged,
            points: r
                .outliers
                .iter()
                .map(|o| OutlierDoc {
                    line: o.line,
                    config: o.config.clone(),
                    target: o.target.clone(),
                    split: split_name(o.validation),
                    residual: o.residual,
                    sigmas: o.sigmas,
                })
                .collect(),
            given_back: r
                .given_back
                .iter()
                .map(|g| GivenBackDoc {
                    line: g.line,
                    config: g.config.clone(),
                    target: g.target.clone(),
                    split: split_name(g.validation),
                    before: JudgedDoc::from(&g.before),
                    after: JudgedDoc::from(&g.after),
                    reason: g.reason(),
                })
                .collect(),
        }
    }
}

/// A residual test (JSON `verdict.test`, `diagnosis.geometric_test`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TestDoc {
    /// `chi-square`, `lack-of-fit F` or `none`.
    pub kind: String,
    /// The statistic.
    pub statistic: Option<f64>,
    /// Its degrees of freedom (the second is 0 for chi-square).
    pub dof: (f64, f64),
    /// Its p-value.
    pub p_value: Option<f64>,
    /// RMS 3-D noise behind it (metres).
    pub noise_rms: Option<f64>,
    /// Something significant is left.
    pub significant: bool,
    /// One line.
    pub summary: String,
}

impl From<&ResidualTest> for TestDoc {
    fn from(t: &ResidualTest) -> Self {
        TestDoc {
            kind: match t.kind {
                NoiseTest::KnownSigma => "chi-square".into(),
                NoiseTest::PureError => "lack-of-fit F".into(),
                NoiseTest::None => "none".into(),
            },
            statistic: t.statistic,
            dof: t.dof,
            p_value: t.p_value,
            noise_rms: t.noise_rms,
            significant: t.significant,
            summary: t.summary.clone(),
        }
    }
}

/// Residual structure against one variable, with its bins.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StructureDoc {
    /// `pose order` or a joint name.
    pub variable: String,
    /// The statistic.
    pub statistic: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Significant at the level over the variables.
    pub significant: bool,
    /// `[centre, rms, |mean|]` per bin (the variable's unit, metres).
    pub bins: Vec<(f64, f64, f64)>,
}

impl From<&StructureCheck> for StructureDoc {
    fn from(s: &StructureCheck) -> Self {
        StructureDoc {
            variable: s.variable.clone(),
            statistic: s.statistic,
            p_value: s.p_value,
            significant: s.significant,
            bins: s.bins.clone(),
        }
    }
}

/// The verdict on the final model (JSON `verdict`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerdictDoc {
    /// `model complete`, `residual remains: N x the floor`, `residual remains` or
    /// `no test possible`.
    pub summary: String,
    /// `true`/`false`, `null` without a test.
    pub complete: Option<bool>,
    /// Final RMS over the noise floor (for a 6-DoF set, position and orientation together,
    /// each over its own noise).
    pub ratio: Option<f64>,
    /// For a 6-DoF set: the position's ratio alone.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_ratio: Option<f64>,
    /// For a 6-DoF set: the orientation's ratio alone (angle RMS over its floor).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_ratio: Option<f64>,
    /// Level of the test.
    pub alpha: f64,
    /// The test.
    pub test: TestDoc,
    /// Structure of the final residual.
    pub structure: Vec<StructureDoc>,
    /// What it means.
    pub notes: Vec<String>,
}

impl From<&Verdict> for VerdictDoc {
    fn from(v: &Verdict) -> Self {
        VerdictDoc {
            summary: v.summary.clone(),
            complete: v.complete,
            ratio: v.ratio,
            position_ratio: v.angle_ratio.and(v.position_ratio),
            angle_ratio: v.angle_ratio,
            alpha: v.alpha,
            test: TestDoc::from(&v.test),
            structure: v.structure.iter().map(StructureDoc::from).collect(),
            notes: v.notes.clone(),
        }
    }
}

/// One full refit of a candidate (JSON `diagnosis.rounds[].trials`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrialDoc {
    /// The effect's label.
    pub label: String,
    /// Calibration RMS with it (metres; `null` when not refitted).
    pub rms: Option<f64>,
    /// Held-out RMS with it (metres).
    pub val_rms: Option<f64>,
    /// F-to-enter and its p-value.
    pub f: f64,
    /// p-value of `f`.
    pub f_p: f64,
    /// The level `f_p` had to beat.
    pub f_threshold: f64,
    /// BIC before and after (`null` when not refitted).
    pub bic: (Option<f64>, Option<f64>),
    /// Held-out test statistic and p-value.
    pub held_out: Option<(f64, f64)>,
    /// Taken or not.
    pub accepted: bool,
    /// Why.
    pub reason: String,
}

/// One selection round: every candidate's scores and the refits tried.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoundDoc {
    /// Calibration RMS at the round's start (metres).
    pub rms: f64,
    /// Held-out RMS at the round's start (metres).
    pub val_rms: Option<f64>,
    /// Every candidate with its scores, best first.
    pub candidates: Vec<CandidateDoc>,
    /// The refits, in order.
    pub trials: Vec<TrialDoc>,
}

/// The diagnosis of `--effects` (JSON `diagnosis`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DiagnosisDoc {
    /// The selection rule.
    pub rule: String,
    /// Level of every test.
    pub alpha: f64,
    /// The test after the geometric step.
    pub geometric_test: TestDoc,
    /// The rounds.
    pub rounds: Vec<RoundDoc>,
    /// Structure of the final residual (the same as the verdict's at the same level).
    pub structure: Vec<StructureDoc>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl From<&Diagnosis> for DiagnosisDoc {
    fn from(d: &Diagnosis) -> Self {
        DiagnosisDoc {
            rule: d.rule.clone(),
            alpha: d.alpha,
            geometric_test: TestDoc::from(&d.residual_test),
            rounds: d
                .rounds
                .iter()
                .map(|r| RoundDoc {
                    rms: r.rms,
                    val_rms: r.val_rms,
                    candidates: r.candidates.iter().map(CandidateDoc::from).collect(),
                    trials: r
                        .trials
                        .iter()
                        .map(|t| TrialDoc {
                            label: t.label.clone(),
                            rms: finite(t.rms),
                            val_rms: t.val_rms,
                            f: t.f,
                            f_p: t.f_p,
                            f_threshold: t.f_threshold,
                            bic: (finite(t.bic.0), finite(t.bic.1)),
                            held_out: t.held_out,
                            accepted: t.accepted,
                            reason: t.reason.clone(),
                        })
                        .collect(),
                })
                .collect(),
            structure: d.structure.iter().map(StructureDoc::from).collect(),
        }
    }
}

/// The JSON documents of `report`'s findings: outliers, verdict, diagnosis.
pub fn documents(report: &Report) -> (Option<OutliersDoc>, VerdictDoc, Option<DiagnosisDoc>) {
    (
        report.outliers.as_ref().map(OutliersDoc::from),
        VerdictDoc::from(&report.verdict),
        report.diagnosis.as_ref().map(DiagnosisDoc::from),
    )
}
