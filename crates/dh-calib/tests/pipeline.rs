//! The calibration pipeline through its public API ([`dh_calib::pipeline`]): a set simulated on
//! a fixture robot's URDF, calibrated as `urdf-dh calibrate` does, its report a plain document.

use dh_calib::pipeline::{
    calibrate, Calibration, CalibrationDoc, EffectsChoice, Names, PathKind, PipelineError,
    PipelineOptions, Plan, Progress, Silent, Start,
};
use dh_calib::simulate::{simulate, Errors, SimulationOptions};
use dh_core::{Convention, DhTable, Tolerance};

/// The UR5 fixture's chain as a standard DH table (the URDF's own extraction).
fn ur5() -> DhTable {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/robots/ur5/robot.urdf"
    );
    let urdf = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let model = urdf_axes::UrdfModel::parse(&urdf).unwrap_or_else(|e| panic!("{e}"));
    let chain = model.chain(None, None).unwrap_or_else(|e| panic!("{e}"));
    dh_core::extract(
        chain.axes(),
        &chain.tip_pose(),
        Tolerance::default(),
        Convention::Standard,
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .table
}

/// Records what the pipeline says of its progress.
#[derive(Default)]
struct Recorder {
    plans: Vec<Plan>,
    finished: usize,
}

impl Progress for Recorder {
    fn started(&mut self, plan: &Plan) {
        self.plans.push(plan.clone());
    }
    fn finished(&mut self) {
        self.finished += 1;
    }
}

const SIGMA: f64 = 5e-5;

fn options() -> PipelineOptions {
    PipelineOptions {
        names: Names {
            model: "robot.urdf".into(),
            data: "simulated".into(),
            validate: None,
        },
        ..PipelineOptions::default()
    }
}

#[test]
fn a_simulated_set_calibrates_down_to_its_noise_and_the_report_round_trips() {
    let nominal = ur5();
    let (data, truth) = simulate(
        &nominal,
        &SimulationOptions {
            poses: 60,
            sigma: SIGMA,
            target_count: 2,
            errors: Errors::Random {
                length: 1e-3,
                angle: 1e-3,
            },
            ..Default::default()
        },
    )
    .unwrap();
    let mut progress = Recorder::default();
    let c = match calibrate(
        &Start::Serial(nominal.clone()),
        &data,
        &options(),
        &mut progress,
    ) {
        Ok(Calibration::Points(c)) => c,
        other => panic!("expected a serial calibration, found {other:?}"),
    };
    assert_eq!(progress.finished, 1);
    let [plan] = progress.plans.as_slice() else {
        panic!("expected one plan, found {:?}", progress.plans);
    };
    assert_eq!(plan.kind, PathKind::Points);
    assert_eq!(plan.samples, c.doc.samples);
    let doc = &c.doc;
    assert_eq!(doc.model, "robot.urdf");
    assert_eq!(doc.steps.len(), 2);
    assert_eq!(doc.steps[1].label, "geometric");
    // The 3-D residual of noise alone is sigma·√3 (a little less: the fit absorbs some); the
    // nominal model is millimetres off.
    let floor = SIGMA * 3f64.sqrt();
    assert!(
        doc.rms_after > 0.8 * floor && doc.rms_after < 1.2 * floor,
        "RMS {} m against a noise floor of {floor} m",
        doc.rms_after
    );
    assert!(doc.rms_before > 10.0 * floor, "{}", doc.rms_before);
    let val = doc.val_rms_after.expect("k-fold validation");
    assert!(val < 1.5 * floor, "validation RMS {val} m");
    // The calibrated model is the fitted one, and close to the truth at the sampled poses.
    assert_eq!(
        c.report.calibrated,
        Calibration::Points(c.clone()).calibrated_table()
    );
    let worst = data
        .samples
        .iter()
        .map(|s| {
            let fit = c.report.calibrated.fk(&s.q).unwrap();
            let real = truth.table.fk(&s.q).unwrap();
            let (dp, _) = dh_core::pose::pose_error(&fit, &real);
            dp
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-3, "tool {worst} m from the truth");
    // The document round-trips through JSON.
    let json = serde_json::to_string_pretty(doc).unwrap();
    let back: CalibrationDoc = serde_json::from_str(&json).unwrap();
    same(
        &serde_json::to_value(&back).unwrap(),
        &serde_json::to_value(doc).unwrap(),
        "",
    );
    assert_eq!(
        Calibration::Points(c.clone()).to_json().unwrap(),
        json,
        "the result's JSON is the document's"
    );
}

/// `a` and `b` hold the same keys, strings and counts, and numbers equal to the last bits:
/// serde_json's default parser may round a decimal one unit in the last place off.
fn same(a: &serde_json::Value, b: &serde_json::Value, at: &str) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (x - y).abs() <= 4.0 * f64::EPSILON * x.abs().max(y.abs()),
                "{at}: {x} against {y}"
            );
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}");
            for (i, (x, y)) in x.iter().zip(y).enumerate() {
                same(x, y, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(
                x.keys().collect::<Vec<_>>(),
                y.keys().collect::<Vec<_>>(),
                "{at}"
            );
            for (k, v) in x {
                same(v, &y[k], &format!("{at}.{k}"));
            }
        }
        (x, y) => assert_eq!(x, y, "{at}"),
    }
}

#[test]
fn an_unknown_effect_is_a_typed_error_naming_the_label() {
    let nominal = ur5();
    let (data, _) = simulate(
        &nominal,
        &SimulationOptions {
            poses: 20,
            ..Default::default()
        },
    )
    .unwrap();
    let options = PipelineOptions {
        effects: EffectsChoice::List(vec!["gear_ratio:no_such_joint".into()]),
        ..options()
    };
    match calibrate(&Start::Serial(nominal), &data, &options, &mut Silent) {
        Err(PipelineError::Effect { label, .. }) => assert_eq!(label, "gear_ratio:no_such_joint"),
        other => panic!("expected an effect error, found {other:?}"),
    }
}

#[test]
fn too_few_samples_are_refused_before_any_fit() {
    let nominal = ur5();
    let (mut data, _) = simulate(
        &nominal,
        &SimulationOptions {
            poses: 20,
            target_count: 2,
            ..Default::default()
        },
    )
    .unwrap();
    data.samples.truncate(4);
    let mut progress = Recorder::default();
    match calibrate(&Start::Serial(nominal), &data, &options(), &mut progress) {
        Err(PipelineError::TooFewSamples { needed, found, .. }) => {
            assert_eq!((needed, found), (5, 4));
        }
        other => panic!("expected too few samples, found {other:?}"),
    }
    assert!(progress.plans.is_empty());
}
