//! Unit tests of `calibrate`.

use super::*;
use dh_workflows::fit::{unit_of, EffectsChoice};

#[test]
fn standard_errors_below_the_printed_digits_switch_to_scientific() {
    let units = DataUnits {
        length: LengthUnit::M,
        angle: AngleUnit::Rad,
    };
    assert_eq!(std_error(2.5e-5, "m", units), "0.000025");
    assert_eq!(std_error(1.3e-7, "m", units), "1.3e-7");
    assert_eq!(std_error(0.0, "m", units), "0.000000");
    assert_eq!(std_error(4e-9, "rad", units), "4.0e-9");
    let mm = DataUnits {
        length: LengthUnit::Mm,
        angle: AngleUnit::Deg,
    };
    assert_eq!(std_error(1.3e-7, "m", mm), "1.3e-4");
}

#[test]
fn effects_choice_parses() {
    assert_eq!("none".parse(), Ok(EffectsChoice::None));
    assert_eq!("auto".parse(), Ok(EffectsChoice::Auto));
    assert_eq!(
        "gear_ratio:j2, gear_ratio:j3".parse(),
        Ok(EffectsChoice::List(vec![
            "gear_ratio:j2".into(),
            "gear_ratio:j3".into()
        ]))
    );
}

#[test]
fn units_of_parameters() {
    assert_eq!(unit_of("joint_2.a"), "m");
    assert_eq!(unit_of("joint_2.beta"), "rad");
    assert_eq!(unit_of("target.SMR1.z"), "m");
    assert_eq!(unit_of("device.rz"), "rad");
    assert_eq!(unit_of("gear_ratio:joint_2"), "rad/rad");
}
