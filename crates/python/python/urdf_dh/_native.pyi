"""Type stubs of the Rust extension ``urdf_dh._native`` (use the ``urdf_dh`` package instead)."""

from typing import Dict, List, Optional, Tuple

Matrix = List[List[float]]
RowTuple = Tuple[
    str, str, float, float, float, float, Optional[float], Optional[float],
    Optional[Tuple[str, float, float]],
]

# Measurements or joint values as arrays: joint names, joint values (rows x joints) and points
# (rows x 3, empty for joint values) flattened row-major, the sigma column or None, the text
# columns (target, config, session, set) by name, and a 6-DoF device's qw, qx, qy, qz (rows x 4
# flattened, NaN rows for points) and sigma_rot, or None, the per-axis sigmas sx, sy, sz
# (rows x 3 flattened) or None, and each row's time (seconds, NaN for none) or None.
Arrays = Tuple[
    List[str],
    List[float],
    List[float],
    Optional[List[float]],
    Dict[str, List[str]],
    Optional[List[float]],
    Optional[List[float]],
    Optional[List[float]],
    Optional[List[float]],
]

RESERVED_COLUMNS: List[str]
CHECK_LINEAR: float
CHECK_ANGULAR: float
DEFAULT_LINEAR: float
DEFAULT_ANGULAR: float

class UrdfDhError(ValueError):
    """Bad input: the CLI's message; ``hint`` its ``hint:`` line or None."""

    hint: Optional[str]

class NativeTable:
    def rows(self) -> List[RowTuple]: ...
    def base(self) -> Matrix: ...
    def tool(self) -> Matrix: ...
    def convention(self) -> str: ...
    def yaml(self) -> str: ...
    def sheet_json(self) -> str: ...
    def verification_json(self) -> str: ...
    def warnings(self) -> List[str]: ...
    def poe_json(self) -> str: ...
    def failure(self) -> Optional[str]: ...
    def fk(self, q: List[float]) -> Matrix: ...

def extract(
    source: str,
    is_xml: bool,
    base: Optional[str],
    tip: Optional[str],
    convention_name: str,
    samples: str,
    seed: str,
    linear: str,
    angular: str,
    xacro_args: Optional[List[Tuple[str, str]]] = ...,
    packages: Optional[List[Tuple[str, str]]] = ...,
) -> NativeTable: ...
def check(
    source: str,
    is_xml: bool,
    sheet: str,
    base: Optional[str],
    tip: Optional[str],
    linear: str,
    angular: str,
    xacro_args: Optional[List[Tuple[str, str]]] = ...,
    packages: Optional[List[Tuple[str, str]]] = ...,
) -> str: ...
def run(argv: List[str]) -> Tuple[str, str, bool]: ...
def calibrate(
    model: Optional[str],
    data_name: str,
    data: Optional[Arrays],
    validate_name: Optional[str],
    validate: Optional[Arrays],
    base: Optional[str],
    tip: Optional[str],
    effects: Optional[str],
    max_effects: Optional[str],
    alpha: Optional[str],
    targets: List[str],
    sigma: Optional[str],
    folds: Optional[str],
    keep_outliers: bool,
    inertials: Optional[str],
    length_unit: str,
    angle_unit: str,
    out: Optional[str],
) -> Tuple[str, str, bool]:
    """(JSON report, warnings, whether the written model failed its proof)."""
def predict(
    model: str,
    joints_name: str,
    joints: Optional[Arrays],
    base: Optional[str],
    tip: Optional[str],
    targets: List[str],
    frame_name: Optional[str],
    session: Optional[str],
    length_unit: str,
    angle_unit: str,
    sequence: bool,
    branch: Optional[str] = None,
) -> Tuple[
    List[str],
    List[str],
    Optional[List[str]],
    List[Tuple[float, float, float]],
    Optional[List[Tuple[float, float, float]]],
    Optional[List[List[float]]],
    str,
    List[str],
]:
    """(targets, configs, sessions or None, positions, tool rpy or None, uncertainties or None,
    frame ("device" or "base"), warnings); lengths and angles in the units given."""
def compensate(
    nominal: str,
    model: str,
    joints_name: str,
    joints: Optional[Arrays],
    base: Optional[str],
    tip: Optional[str],
    position_only: bool,
    max_change: Optional[str],
    length_unit: str,
    angle_unit: str,
    sequence: bool,
    branch: Optional[str] = None,
) -> Tuple[List[List[float]], List[Tuple[float, float, float, float]], List[str], List[str]]:
    """(corrected joint values, per pose position_before, orientation_before, position_error,
    orientation_error, the poses not compensated as `config (line N): why`, warnings); in the
    units given."""
def measured_joints(model: str, base: Optional[str] = None, tip: Optional[str] = None) -> List[str]: ...
def simulate(
    model: str,
    base: Optional[str],
    tip: Optional[str],
    poses: str,
    noise: str,
    orientation_noise: Optional[str],
    cpa: bool,
    arc: Optional[str],
    effects: List[str],
    errors: List[str],
    random_errors: Optional[str],
    targets: str,
    repeats: str,
    validation: str,
    sessions: str,
    seed: int,
    data_name: str,
    truth_name: str,
    gravity: Optional[List[str]] = None,
) -> Tuple[str, str, str, str]: ...
def write_outputs(
    inputs: List[Tuple[str, str]],
    outputs: List[Tuple[str, str, str]],
) -> None: ...
CPA_LINEAR: float
CPA_ANGULAR: float
def cpa(
    data_name: str,
    data: Optional[Arrays],
    model: Optional[str],
    base: Optional[str],
    tip: Optional[str],
    convention: str,
    linear_tol: float,
    angular_tol: float,
    length_unit: str,
    angle_unit: str,
) -> Tuple[str, str, str]: ...
