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

/// The parameter table prints an effect's unit as the JSON names it (`ln s` for
/// `thermal_growth.ln_tau`, not `1`), lengths and angles in the data's units.
#[test]
fn the_parameter_table_prints_each_effects_own_unit() {
    let units = DataUnits {
        length: LengthUnit::Mm,
        angle: AngleUnit::Deg,
    };
    assert_eq!(unit_label("ln s", units), "ln s");
    assert_eq!(unit_label("ln session", units), "ln session");
    assert_eq!(unit_label("1/m^2", units), "1/m^2");
    assert_eq!(unit_label("rad/(N m)", units), "rad/(N m)");
    assert_eq!(unit_label("1", units), "1");
    assert_eq!(unit_label("m", units), "mm");
    assert_eq!(unit_label("rad", units), "deg");
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
