//! The cases of the bad-input corpus: each a snapshot name, the arguments of one run and the
//! exit code it must give (2 for an error, 0 or 1 where the input only warns).

/// A case: its snapshot name, the arguments, and the exit code it must give.
pub(super) struct Case {
    pub(super) name: &'static str,
    pub(super) args: &'static [&'static str],
    pub(super) exit: i32,
}

const fn case(name: &'static str, args: &'static [&'static str]) -> Case {
    Case {
        name,
        args,
        exit: 2,
    }
}

const fn warns(name: &'static str, args: &'static [&'static str], exit: i32) -> Case {
    Case { name, args, exit }
}

macro_rules! urdf {
    ($name:literal) => {
        case(
            concat!("urdf_", $name),
            &["extract", concat!("fixtures/invalid/urdf/", $name, ".urdf")],
        )
    };
}

macro_rules! xacro {
    ($name:literal) => {
        case(
            concat!("xacro_", $name),
            &[
                "extract",
                concat!("fixtures/invalid/xacro/", $name, ".urdf.xacro"),
            ],
        )
    };
}

macro_rules! sheet {
    ($name:literal, $file:literal) => {
        case(
            concat!("sheet_", $name),
            &[
                "check",
                "fixtures/invalid/urdf/valid_arm.urdf",
                "--sheet",
                concat!("fixtures/invalid/sheet/", $file),
            ],
        )
    };
}

/// A tree sheet, read by `calibrate` (the only command that reads trees) with the valid
/// arm's data.
macro_rules! tree {
    ($name:literal) => {
        case(
            concat!("sheet_", $name),
            &[
                "calibrate",
                "--model",
                concat!("fixtures/invalid/sheet/", $name, ".yaml"),
                "--data",
                "fixtures/invalid/csv/valid_arm.csv",
            ],
        )
    };
}

macro_rules! csv {
    ($name:literal) => {
        case(
            concat!("csv_", $name),
            &[
                "calibrate",
                "--model",
                "fixtures/invalid/urdf/valid_arm.urdf",
                "--data",
                concat!("fixtures/invalid/csv/", $name, ".csv"),
            ],
        )
    };
}

const VALID_ARM: &str = "fixtures/invalid/urdf/valid_arm.urdf";
const VALID_SHEET: &str = "fixtures/invalid/sheet/valid_arm.yaml";
const VALID_CSV: &str = "fixtures/invalid/csv/valid_arm.csv";

pub(super) const CASES: &[Case] = &[
    xacro!("undefined_property"),
    xacro!("macro_recursion"),
    xacro!("include_cycle"),
    xacro!("missing_package"),
    xacro!("division_by_zero"),
    xacro!("undefined_argument"),
    // Not a URDF at all.
    urdf!("empty"),
    urdf!("not_xml"),
    urdf!("truncated"),
    urdf!("not_utf8"),
    urdf!("comment_with_double_dash"),
    urdf!("mismatched_tag"),
    urdf!("wrong_root"),
    urdf!("deep_nesting"),
    urdf!("entity_bomb"),
    urdf!("control_character"),
    urdf!("raw_lt_in_attribute"),
    // Not one tree of uniquely named links.
    urdf!("no_links"),
    urdf!("duplicate_link"),
    urdf!("duplicate_joint"),
    urdf!("control_character_in_name"),
    urdf!("bidi_in_name"),
    urdf!("two_parents"),
    urdf!("cycle"),
    urdf!("cycle_without_root"),
    urdf!("several_roots"),
    urdf!("missing_link"),
    urdf!("missing_parent_element"),
    // Numbers.
    urdf!("bad_number"),
    urdf!("zero_axis"),
    urdf!("nan_axis"),
    urdf!("infinite_origin"),
    urdf!("nan_rpy"),
    urdf!("nan_limit"),
    urdf!("infinite_limit"),
    urdf!("reversed_limits"),
    urdf!("missing_limit"),
    urdf!("overflowing_origins"),
    urdf!("huge_origin"),
    // Joints.
    urdf!("spherical_joint"),
    urdf!("unknown_joint_type"),
    urdf!("mimic_missing_joint"),
    urdf!("mimic_itself"),
    urdf!("mimic_cycle"),
    urdf!("mimic_fixed"),
    urdf!("floating_joint"),
    urdf!("planar_joint"),
    urdf!("no_moving_joint"),
    // Faults that cannot change the chain's kinematics: warnings, as urdfdom reads them.
    warns(
        "urdf_off_chain_faults",
        &["extract", "fixtures/invalid/urdf/off_chain_faults.urdf"],
        0,
    ),
    // Choosing the chain: the default tip is the end of the longest arm (tool0 here, beside a
    // camera and 20 sensors); two arms of one length are refused.
    warns(
        "urdf_several_leaves",
        &["extract", "fixtures/invalid/urdf/several_leaves.urdf"],
        0,
    ),
    warns(
        "urdf_many_leaves",
        &["extract", "fixtures/invalid/urdf/many_leaves.urdf"],
        0,
    ),
    urdf!("two_arms"),
    case("arg_unknown_tip", &["extract", VALID_ARM, "--tip", "tool"]),
    case(
        "arg_unknown_base",
        &["extract", VALID_ARM, "--base", "world"],
    ),
    case(
        "arg_unknown_tip_among_many_links",
        &[
            "extract",
            "fixtures/invalid/urdf/many_leaves.urdf",
            "--tip",
            "gripper",
        ],
    ),
    case(
        "arg_tip_above_base",
        &["extract", VALID_ARM, "--base", "link_2", "--tip", "link_1"],
    ),
    case(
        "arg_tip_on_another_branch",
        &[
            "extract",
            "fixtures/invalid/urdf/several_leaves.urdf",
            "--base",
            "link_2",
            "--tip",
            "camera_link",
        ],
    ),
    case(
        "arg_base_is_tip",
        &["extract", VALID_ARM, "--base", "tool0", "--tip", "tool0"],
    ),
    case(
        "arg_missing_file",
        &["extract", "fixtures/invalid/urdf/no_such_file.urdf"],
    ),
    // Sheets, read by `check` against the valid arm.
    sheet!("empty", "empty.yaml"),
    sheet!("not_yaml", "not_yaml.yaml"),
    // A measurement CSV given as a sheet: what it looks like and one line, not the whole file.
    sheet!("measurements_as_sheet", "measurements_as_sheet.csv"),
    sheet!("truncated_json", "truncated.json"),
    sheet!("not_utf8", "not_utf8.yaml"),
    sheet!("not_a_mapping", "not_a_mapping.yaml"),
    sheet!("missing_field", "missing_field.yaml"),
    sheet!("missing_convention", "missing_convention.yaml"),
    sheet!("unknown_convention", "unknown_convention.yaml"),
    sheet!("wrong_length_unit", "wrong_length_unit.yaml"),
    sheet!("wrong_angle_unit", "wrong_angle_unit.yaml"),
    sheet!("unknown_key", "unknown_key.yaml"),
    sheet!("duplicate_key", "duplicate_key.yaml"),
    sheet!("nan_value", "nan_value.yaml"),
    sheet!("infinite_value", "infinite_value.yaml"),
    sheet!("huge_value", "huge_value.yaml"),
    sheet!(
        "beta_beyond_a_right_angle",
        "beta_beyond_a_right_angle.yaml"
    ),
    sheet!("text_value", "text_value.yaml"),
    sheet!("duplicate_joint", "duplicate_joint.yaml"),
    sheet!("reversed_limits", "reversed_limits.yaml"),
    sheet!("half_limits", "half_limits.yaml"),
    sheet!("no_joints", "no_joints.yaml"),
    sheet!("spherical_joint", "spherical_joint.yaml"),
    sheet!("short_pose", "short_pose.yaml"),
    sheet!("mimic_itself", "mimic_itself.yaml"),
    sheet!("mimic_cycle", "mimic_cycle.yaml"),
    // An angle beyond a turn is read as the same angle within half a turn, with a warning,
    // and the converted table proves (999999 rad failed the proofs of convert and to-urdf).
    warns(
        "sheet_theta_beyond_a_turn",
        &[
            "convert",
            "fixtures/invalid/sheet/theta_beyond_a_turn.yaml",
            "--to",
            "modified",
            "--format",
            "csv",
        ],
        0,
    ),
    sheet!("alias_bomb", "alias_bomb.yaml"),
    sheet!(
        "control_character_in_name",
        "control_character_in_name.yaml"
    ),
    sheet!("deep_nesting", "deep_nesting.yaml"),
    sheet!("unclosed_nesting", "unclosed_nesting.yaml"),
    sheet!("missing_file", "no_such_sheet.yaml"),
    sheet!("bidi_in_name", "bidi_in_name.yaml"),
    sheet!("blank_name", "blank_name.yaml"),
    sheet!("base_beyond_si_limit", "base_beyond_si_limit.yaml"),
    case(
        "sheet_conversion_overflow",
        &[
            "convert",
            "fixtures/invalid/sheet/conversion_overflow.yaml",
            "--to",
            "standard",
        ],
    ),
    case(
        "sheet_deep_inertials",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/valid_arm.csv",
            "--inertials",
            "fixtures/invalid/sheet/deep_inertials.yaml",
        ],
    ),
    // Writers refuse what their readers would: to-urdf names and limits.
    case(
        "to_urdf_joint_named_like_tip_joint",
        &[
            "to-urdf",
            "fixtures/invalid/sheet/joint_named_like_tip_joint.yaml",
        ],
    ),
    case(
        "to_urdf_prismatic_without_limits",
        &[
            "to-urdf",
            "fixtures/invalid/sheet/prismatic_without_limits.yaml",
        ],
    ),
    case(
        "to_urdf_tip_link_is_a_joint_link",
        &["to-urdf", VALID_SHEET, "--tip-link", "joint_1_link"],
    ),
    case(
        "to_urdf_base_link_is_tip_link",
        &[
            "to-urdf",
            VALID_SHEET,
            "--base-link",
            "tool0",
            "--tip-link",
            "tool0",
        ],
    ),
    case(
        "to_urdf_tab_in_link",
        &["to-urdf", VALID_SHEET, "--tip-link", "tool\t0"],
    ),
    // Tree sheets: `check` refuses one; `calibrate` names the file, line, branch and joint.
    sheet!("tree_in_check", "tree_in_check.yaml"),
    tree!("tree_unknown_key_in_branch"),
    tree!("tree_duplicate_joint"),
    tree!("tree_empty_branch"),
    tree!("tree_coupled_unknown_driver"),
    tree!("tree_inertials_unknown_joint"),
    tree!("tree_reversed_limits_in_branch"),
    tree!("tree_target_on_no_branch"),
    // Measurement CSVs, read by `calibrate` with the valid arm as the model.
    csv!("empty"),
    csv!("only_header"),
    csv!("not_utf8"),
    csv!("missing_joint_column"),
    csv!("missing_coordinate"),
    csv!("duplicate_column"),
    csv!("sigma_conflict"),
    csv!("short_row"),
    csv!("unterminated_quote"),
    csv!("non_numeric_cell"),
    csv!("nan_cell"),
    csv!("infinite_cell"),
    csv!("negative_sigma"),
    csv!("unknown_set"),
    csv!("mm_as_m"),
    csv!("deg_as_rad"),
    csv!("mixed_units"),
    csv!("too_few_poses"),
    // Hostile names and magnitudes (issue 11): refused, the name escaped in the message.
    csv!("escape_in_target"),
    csv!("bidi_in_target"),
    csv!("nul_in_config"),
    csv!("huge_sigma"),
    csv!("tiny_sigma"),
    csv!("subnormal_sigma"),
    csv!("target_per_row"),
    case(
        "csv_huge_mm_coordinate",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/huge_mm_coordinate.csv",
            "--length-unit",
            "mm",
        ],
    ),
    case(
        "csv_missing_file",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/no_such_data.csv",
        ],
    ),
    case(
        "csv_unknown_target",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/valid_arm.csv",
            "--targets",
            "t2",
        ],
    ),
    // Usage errors.
    case(
        "arg_unknown_option",
        &["extract", VALID_ARM, "--tpi", "tool0"],
    ),
    case(
        "arg_not_a_number",
        &["extract", VALID_ARM, "--samples", "many"],
    ),
    case(
        "arg_nan_tolerance",
        &["extract", VALID_ARM, "--linear-tol", "nan"],
    ),
    // Every numeric option is range-checked by its parser, which names option and range.
    case(
        "arg_angular_tolerance_too_large",
        &["extract", VALID_ARM, "--angular-tol", "4"],
    ),
    case(
        "arg_check_linear_tolerance_too_large",
        &[
            "check",
            VALID_ARM,
            "--sheet",
            VALID_SHEET,
            "--linear-tol",
            "2",
        ],
    ),
    case(
        "arg_samples_too_many",
        &["extract", VALID_ARM, "--samples", "1000000000"],
    ),
    case(
        "arg_nan_joint_value",
        &[
            "extract",
            VALID_ARM,
            "--svg",
            "fixtures/invalid/never_written.svg",
            "--q",
            "nan,0",
        ],
    ),
    case(
        "arg_huge_sigma",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            VALID_CSV,
            "--sigma",
            "1e200",
        ],
    ),
    case(
        "arg_tiny_sigma",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            VALID_CSV,
            "--sigma",
            "1e-300",
        ],
    ),
    // A proof of no sample is no proof: every proof's count is in [1, 1e6].
    case(
        "arg_samples_zero_convert",
        &["convert", VALID_SHEET, "--to", "modified", "--samples", "0"],
    ),
    case(
        "arg_samples_zero_to_urdf",
        &["to-urdf", VALID_SHEET, "--samples", "0"],
    ),
    case(
        "arg_samples_zero_batch",
        &["batch", "fixtures/invalid/never_read.txt", "--samples", "0"],
    ),
    case(
        "arg_samples_too_many_convert",
        &[
            "convert",
            VALID_SHEET,
            "--to",
            "modified",
            "--samples",
            "1000000001",
        ],
    ),
    case(
        "arg_zero_folds",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            VALID_CSV,
            "--folds",
            "0",
        ],
    ),
    case(
        "arg_alpha_above_half",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            VALID_CSV,
            "--alpha",
            "0.7",
        ],
    ),
    case(
        "arg_alpha_zero",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            VALID_CSV,
            "--alpha",
            "0",
        ],
    ),
    case(
        "arg_too_many_poses",
        &[
            "simulate",
            "--model",
            VALID_ARM,
            "--out",
            "fixtures/invalid/never_written.csv",
            "--poses",
            "100000000",
        ],
    ),
    case(
        "arg_too_many_samples_in_all",
        &[
            "simulate",
            "--model",
            VALID_ARM,
            "--out",
            "fixtures/invalid/never_written.csv",
            "--poses",
            "1000000",
            "--targets",
            "10",
        ],
    ),
    case(
        "arg_escape_in_tip",
        &["extract", VALID_ARM, "--tip", "\u{1b}[2Jtool0"],
    ),
    // Readable but suspicious: a warning, and the comparison's own verdict.
    warns(
        "sheet_mm_as_m",
        &[
            "check",
            VALID_ARM,
            "--sheet",
            "fixtures/invalid/sheet/mm_as_m.yaml",
        ],
        1,
    ),
    warns(
        "sheet_deg_as_rad",
        &[
            "check",
            VALID_ARM,
            "--sheet",
            "fixtures/invalid/sheet/deg_as_rad.yaml",
        ],
        1,
    ),
    warns(
        "sheet_mimic_missing_joint",
        &[
            "convert",
            "fixtures/invalid/sheet/mimic_missing_joint.yaml",
            "--to",
            "modified",
        ],
        0,
    ),
    warns(
        "csv_valid_arm",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/valid_arm.csv",
        ],
        0,
    ),
    warns(
        "urdf_zero_limits",
        &["extract", "fixtures/invalid/urdf/zero_limits.urdf"],
        0,
    ),
    warns(
        "csv_zero_sigma",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/zero_sigma.csv",
        ],
        0,
    ),
    warns(
        "csv_deg_below_four_turns",
        &[
            "calibrate",
            "--model",
            VALID_ARM,
            "--data",
            "fixtures/invalid/csv/deg_below_four_turns.csv",
        ],
        0,
    ),
    warns(
        "sheet_bom",
        &[
            "check",
            VALID_ARM,
            "--sheet",
            "fixtures/invalid/sheet/bom.yaml",
        ],
        0,
    ),
    // Loose tolerances snap the tilted pair; the table misses the URDF by centimetres, which
    // is never a pass (the bound is capped at 1 mm, 1 mrad).
    warns(
        "urdf_tilted_axes_with_loose_tolerances",
        &[
            "extract",
            "fixtures/invalid/urdf/tilted_axes.urdf",
            "--angular-tol",
            "0.1",
            "--linear-tol",
            "0.1",
            "--samples",
            "100",
        ],
        1,
    ),
    // The control: the valid pair matches.
    warns(
        "sheet_valid_arm",
        &[
            "check",
            VALID_ARM,
            "--sheet",
            "fixtures/invalid/sheet/valid_arm.yaml",
        ],
        0,
    ),
];
