//! The nominal kinematics of the UR family, shipped with the tool: `data/ur/<model>.yaml`,
//! DH sheets with the source of their numbers (Universal Robots' published DH table; joint
//! limits from Universal Robots' ROS 2 description).

/// A shipped nominal sheet.
#[derive(Clone, Copy, Debug)]
pub struct NominalSheet {
    /// Its name on the command line (`ur5e`).
    pub name: &'static str,
    /// The sheet's YAML text.
    pub text: &'static str,
}

/// Every shipped nominal sheet: CB3 (UR3, UR5, UR10), e-Series (UR3e, UR5e, UR10e, UR16e),
/// UR20 and UR30. (UR15 is not here: no published table of it could be checked.)
pub const NOMINAL: [NominalSheet; 9] = [
    sheet("ur3", include_str!("../../data/ur/ur3.yaml")),
    sheet("ur5", include_str!("../../data/ur/ur5.yaml")),
    sheet("ur10", include_str!("../../data/ur/ur10.yaml")),
    sheet("ur3e", include_str!("../../data/ur/ur3e.yaml")),
    sheet("ur5e", include_str!("../../data/ur/ur5e.yaml")),
    sheet("ur10e", include_str!("../../data/ur/ur10e.yaml")),
    sheet("ur16e", include_str!("../../data/ur/ur16e.yaml")),
    sheet("ur20", include_str!("../../data/ur/ur20.yaml")),
    sheet("ur30", include_str!("../../data/ur/ur30.yaml")),
];

const fn sheet(name: &'static str, text: &'static str) -> NominalSheet {
    NominalSheet { name, text }
}

/// The shipped sheet named `name` (case-insensitive: `UR5e`, `ur5e`).
pub fn nominal(name: &str) -> Option<NominalSheet> {
    NOMINAL
        .iter()
        .find(|s| s.name.eq_ignore_ascii_case(name.trim()))
        .copied()
}
