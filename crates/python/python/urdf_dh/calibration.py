"""Calibration from measured points, and using its result: ``calibrate``, ``predict``,
``compensate``.

Each calls the ``urdf-dh`` library's entry for the command of the same name in process (the Rust
extension), so the results, the checks on the input and the messages are the command line's own.
Measurements may be a file path, a pandas ``DataFrame`` (columns named as in the measurement CSV:
one per joint, ``x``, ``y``, ``z``, optional ``target``, ``config``, ``sigma`` (or ``sx``, ``sy``,
``sz`` per axis), ``set``,
``session``, ``time`` (seconds), and a 6-DoF device's ``qw``, ``qx``, ``qy``, ``qz``, ``sigma_rot``,
NaN in the rows of points) or a numpy array (one column per measured joint of the model in its order, then
``x``, ``y``, ``z``). A DataFrame or an array is handed over as arrays, no file is written: the
library checks its values as it checks a file's cells, and an error names the row (0-based, as
numpy and pandas count) and the column. Units are those of the options (``length_unit``,
``angle_unit``); every report is in metres and radians. Each row's time (seconds, any origin; NaN
for a row without one), which an effect of time (``thermal_growth``) reads, is a DataFrame's
``time`` column or the ``time=`` argument (a 1-D array, one per row), as a file's ``time`` column.
"""

from __future__ import annotations

import contextlib
import json
import os
import warnings
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

PathLike = Union[str, "os.PathLike[str]"]

# Text columns handed over by name; every other reserved column of the CSV layout needs a file.
_LABELS = ("target", "config", "session", "set")
_POINT_COLUMNS = ("x", "y", "z", "sigma")
# Per-axis standard deviations: all three or none, not with sigma.
_AXIS_SIGMAS = ("sx", "sy", "sz")
# A 6-DoF device's orientation: all five or none.
_ORIENTATION = ("qw", "qx", "qy", "qz", "sigma_rot")
# Each row's time (seconds), for effects of time.
_TIME = "time"

# What the library is given for a DataFrame or array: joint names, joint values and points
# (flattened row-major), the sigma column, the text columns, the orientation (qw, qx, qy, qz
# flattened, NaN rows for points), sigma_rot, the per-axis sigmas (sx, sy, sz flattened), and
# each row's time (seconds, NaN for none).
_Arrays = Tuple[
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


def _warn(stderr: str) -> None:
    for line in stderr.splitlines():
        if line.startswith("urdf-dh: warning: "):
            warnings.warn(line[len("urdf-dh: warning: ") :], stacklevel=3)


def _is_path(data: Any) -> bool:
    return isinstance(data, (str, os.PathLike))


def _is_frame(data: Any) -> bool:
    return hasattr(data, "columns") and hasattr(data, "to_numpy")


def _text(values: Any) -> List[str]:
    """A text column's cells: missing ones (NaN, None) empty, others as text."""
    out = []
    for v in values:
        if v is None or (isinstance(v, float) and np.isnan(v)):
            out.append("")
        else:
            out.append(str(v))
    return out


def _frame_arrays(frame: Any, what: str, points: bool, strict: bool) -> _Arrays:
    """The arrays of a DataFrame, its columns used by name. ``points``: measurements (x, y, z,
    sigma read; other reserved columns refused), else joint values (points ignored); ``time``
    read in both. ``strict``: every other column is a joint and must be numeric (no model names
    the joints)."""
    reserved = set(_native.RESERVED_COLUMNS)
    columns = [str(c) for c in frame.columns]
    if points:
        other = [
            c
            for c in columns
            if c in reserved and c not in _LABELS + _POINT_COLUMNS + _ORIENTATION + _AXIS_SIGMAS + (_TIME,)
        ]
        if other:
            raise _native.UrdfDhError(
                f"{what}: column(s) {', '.join(other)} can be read from a CSV file only; pass its path"
            )
        for c in "xyz":
            if c not in columns:
                raise _native.UrdfDhError(f"{what}: missing point column '{c}'; the columns are {', '.join(columns)}")
    names: List[str] = []
    values = []
    for c, original in zip(columns, frame.columns):
        if c in reserved:
            continue
        try:
            values.append(np.asarray(frame[original], dtype=float))
        except (TypeError, ValueError):
            if strict:
                raise _native.UrdfDhError(f"{what}: column '{c}': expected numbers (a joint's values)") from None
            continue
        names.append(c)
    rows = len(frame)
    q = np.column_stack(values) if values else np.zeros((rows, 0))
    xyz = (
        np.column_stack([np.asarray(frame[c], dtype=float) for c in "xyz"]).ravel().tolist()
        if points
        else []
    )
    sigma = np.asarray(frame["sigma"], dtype=float).tolist() if points and "sigma" in columns else None
    labels = {c: _text(frame[c]) for c in _LABELS if c in columns}
    quaternion, sigma_rot, sigma_axes = None, None, None
    if points:
        orientation = _together(frame, columns, _ORIENTATION, what, "orientation columns")
        if orientation is not None:
            quaternion = orientation[:, :4].ravel().tolist()
            sigma_rot = orientation[:, 4].tolist()
        axes = _together(frame, columns, _AXIS_SIGMAS, what, "per-axis sigma columns")
        if axes is not None:
            sigma_axes = axes.ravel().tolist()
    time = _times(frame[_TIME], what) if _TIME in columns else None
    return names, q.ravel().tolist(), xyz, sigma, labels, quaternion, sigma_rot, sigma_axes, time


def _times(values: Any, what: str) -> List[float]:
    """A time column or ``time=`` argument (seconds) as floats: 1-D, numbers (NaN for a row
    without a time); its length and finiteness are checked by the library, by row."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise _native.UrdfDhError(f"{what}: 'time': expected numbers (seconds)") from None
    if array.ndim != 1:
        raise _native.UrdfDhError(f"{what}: 'time': expected a 1-D array (one time per row), found shape {array.shape}")
    return array.tolist()


def _with_time(arrays: Optional[_Arrays], time: Any, what: str, argument: str) -> Optional[_Arrays]:
    """``arrays`` with the times of the ``time=`` argument (named ``argument``): refused beside
    a file (its ``time`` column is read) and beside a DataFrame's own ``time`` column."""
    if time is None:
        return arrays
    if arrays is None:
        raise _native.UrdfDhError(
            f"{argument}: with {what} given as a file, the times are its 'time' column; pass them there"
        )
    if arrays[8] is not None:
        raise _native.UrdfDhError(
            f"{argument}: {what} has a 'time' column already; give the times once"
        )
    return arrays[:8] + (_times(time, what),)  # type: ignore[return-value]


def _together(frame: Any, columns: List[str], group: Sequence[str], what: str, label: str) -> Any:
    """The columns ``group`` of ``frame`` as a (rows x len(group)) float array when all are there,
    None when none is; one without the others is an error naming the missing ones."""
    present = [c for c in group if c in columns]
    if not present:
        return None
    if len(present) != len(group):
        missing = [c for c in group if c not in columns]
        raise _native.UrdfDhError(f"{what}: {label} {', '.join(group)} go together; missing {', '.join(missing)}")
    return np.column_stack([np.asarray(frame[c], dtype=float) for c in group])


def _arrays(
    table: Any, columns: Optional[Sequence[str]], what: str, points: bool, strict: bool
) -> _Arrays:
    """The arrays of a DataFrame (its own columns) or a 2-D array (``columns``, then x, y, z
    when ``points``); ``strict``: no model, a DataFrame's columns are all joints or reserved."""
    if _is_frame(table):
        return _frame_arrays(table, what, points, strict)
    if columns is None:
        raise _native.UrdfDhError(
            f"{what}: a plain array needs a model, whose joints name its columns; pass a DataFrame or a CSV path"
        )
    array = np.asarray(table, dtype=float)
    if array.ndim != 2:
        raise _native.UrdfDhError(
            f"{what}: expected a 2-D array (one row per sample), found shape {array.shape}"
        )
    names = list(columns) + (["x", "y", "z"] if points else [])
    if array.shape[1] != len(names):
        raise _native.UrdfDhError(
            f"{what}: expected {len(names)} columns ({', '.join(names)}), found {array.shape[1]}"
        )
    j = len(columns)
    xyz = array[:, j:].ravel().tolist() if points else []
    return list(columns), array[:, :j].ravel().tolist(), xyz, None, {}, None, None, None, None


def _source(
    data: Any, columns: Optional[Sequence[str]], what: str, points: bool, strict: bool = False
) -> Tuple[str, Optional[_Arrays]]:
    """A file path as is, or a DataFrame / array as arrays named ``<what>`` in messages."""
    if _is_path(data):
        return os.fspath(data), None
    return f"<{what}>", _arrays(data, columns, what, points, strict)


def _joints(model: PathLike, base: Optional[str], tip: Optional[str]) -> List[str]:
    return list(_native.measured_joints(os.fspath(model), base, tip))


def _pose(xyz: Sequence[float], rpy: Sequence[float]) -> np.ndarray:
    """4x4 of URDF xyz / rpy (``R = Rz(yaw) Ry(pitch) Rx(roll)``)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    m = np.eye(4)
    m[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    m[:3, 3] = xyz
    return m


class Report:
    """The result of :func:`calibrate`: the JSON report of ``urdf-dh calibrate --format json``.

    Attributes:
        rms_before, rms_after: calibration RMS (m) of the first and last step.
        val_rms_before, val_rms_after: validation RMS (m), or None.
        steps: one dict per step (``label``, ``free``, ``rms``, ``val_rms``, ...).
        parameters: one dict per parameter (``name``, ``unit``, ``nominal``, ``estimate``,
            ``std_error``, ``free``, ``identified``; beside ``thermal_growth.ln_tau`` a
            ``derived`` dict: ``tau`` = exp(ln_tau) in s with its delta-method standard error).
        selected_effects: labels of the effects estimated in the last step.
        device: ``T_device_base`` (4x4): the robot's base link in the measuring device's frame.
        targets: target name -> position in the tip frame (m).
        verdict, outliers, noise_floor, notes: as in the JSON (dicts, lists, None).
        written: the proof of the file written with ``out=`` (dict), or None.
    """

    def __init__(self, doc: Dict[str, Any]) -> None:
        self._doc = doc
        self.rms_before: float = doc["rms_before"]
        self.rms_after: float = doc["rms_after"]
        self.val_rms_before: Optional[float] = doc.get("val_rms_before")
        self.val_rms_after: Optional[float] = doc.get("val_rms_after")
        self.steps: List[Dict[str, Any]] = list(doc["steps"])
        self.parameters: List[Dict[str, Any]] = list(doc["parameters"])
        self.selected_effects: List[str] = list(doc.get("selected_effects", []))
        device = doc.get("device")
        self.device: Optional[np.ndarray] = (
            None if device is None else _pose(device["xyz"], device["rpy"])
        )
        self.targets: Dict[str, np.ndarray] = {
            t["name"]: np.array(t["xyz"], dtype=float) for t in doc.get("targets", [])
        }
        self.verdict: Any = doc.get("verdict")
        self.outliers: Any = doc.get("outliers")
        self.noise_floor: Any = doc.get("noise_floor")
        self.notes: List[str] = list(doc.get("notes", []))
        self.written: Optional[Dict[str, Any]] = doc.get("written")

    def __repr__(self) -> str:
        return (
            f"<urdf_dh.Report RMS {self.rms_before:.6f} -> {self.rms_after:.6f} m, "
            f"{len(self.steps)} steps>"
        )

    def parameter(self, name: str) -> Dict[str, Any]:
        """The parameter called ``name`` (e.g. ``"elbow_joint.a"``).

        Raises:
            KeyError: no such parameter.
        """
        for p in self.parameters:
            if p["name"] == name:
                return dict(p)
        raise KeyError(name)

    def to_dict(self) -> Dict[str, Any]:
        """The report as ``urdf-dh calibrate --format json`` prints it."""
        return json.loads(json.dumps(self._doc))


def calibrate(
    model: Optional[PathLike],
    data: Any,
    *,
    validate: Any = None,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    effects: Union[None, str, Sequence[str]] = None,
    max_effects: Optional[int] = None,
    alpha: Optional[float] = None,
    targets: Optional[Sequence[str]] = None,
    sigma: Optional[float] = None,
    folds: Optional[int] = None,
    keep_outliers: bool = False,
    inertials: Optional[PathLike] = None,
    length_unit: str = "m",
    angle_unit: str = "rad",
    out: Optional[PathLike] = None,
    time: Any = None,
    validate_time: Any = None,
) -> Report:
    """Fits ``model`` (a URDF or DH sheet path; None: start from circle-point analysis) to
    measured points, as ``urdf-dh calibrate`` does.

    Args:
        data: measurements: a CSV path, a pandas DataFrame (columns by name: joints, x, y, z,
            optional target, config, sigma (or sx, sy, sz per axis), set, session; a 6-DoF
            device's qw, qx, qy, qz, sigma_rot, NaN for points), or a numpy array (the model's
            measured joints, then x, y, z). A DataFrame or array is handed to the library as
            arrays (no file); with model None a DataFrame's non-reserved columns are the joints.
        validate: validation measurements, same forms (a file only beside a file).
        effects: None, ``"auto"``, or effect labels (``["gear_ratio:elbow_joint"]``).
        alpha: level of the effect selection's tests and of the final verdict, in (0, 0.5]
            (default 0.01, ``--alpha``).
        out: write the calibrated model there (a sheet, or a URDF for ``.urdf``), proved as
            written; :func:`predict` and :func:`compensate` read it.
        time: each row's time in seconds (a 1-D array, NaN for a row without one), with
            ``data`` as a DataFrame without a ``time`` column or an array: what
            ``thermal_growth`` reads (``t`` since the first timed row), as a file's ``time``
            column. Without times an effect of time reads the pose order.
        validate_time: the same for ``validate``.
        The other options are the CLI's (``--sigma`` in ``length_unit``, ...).

    Raises:
        FileNotFoundError: a file does not exist.
        UrdfDhError: bad model or data (the CLI's message and ``.hint``; for an array or a
            DataFrame, the 0-based row and the column of a bad value, or a wrong shape), or a
            written model that failed its proof.
    """
    columns = None
    if model is not None and not _is_path(data) and not _is_frame(data):
        columns = _joints(model, base, tip)
    data_name, arrays = _source(data, columns, "data", points=True, strict=model is None)
    arrays = _with_time(arrays, time, "data", "time")
    validate_name, validate_arrays = None, None
    if validate is not None:
        if arrays is None and not _is_path(validate):
            raise _native.UrdfDhError(
                "validate: with data given as a file, give the validation measurements as a file too"
            )
        vcols = columns
        if model is not None and vcols is None and not _is_path(validate) and not _is_frame(validate):
            vcols = _joints(model, base, tip)
        validate_name, validate_arrays = _source(validate, vcols, "validate", points=True, strict=model is None)
        validate_arrays = _with_time(validate_arrays, validate_time, "validate", "validate_time")
    elif validate_time is not None:
        raise _native.UrdfDhError("validate_time: expected it with validate, found no validate")
    if isinstance(effects, str) or effects is None:
        effects_text = effects
    else:
        effects_text = ",".join(effects)
    stdout, stderr, failed = _native.calibrate(
        None if model is None else os.fspath(model),
        data_name,
        arrays,
        validate_name,
        validate_arrays,
        base,
        tip,
        effects_text,
        None if max_effects is None else str(int(max_effects)),
        None if alpha is None else repr(float(alpha)),
        list(targets or []),
        None if sigma is None else repr(float(sigma)),
        None if folds is None else str(int(folds)),
        keep_outliers,
        None if inertials is None else os.fspath(inertials),
        length_unit,
        angle_unit,
        None if out is None else os.fspath(out),
    )
    _warn(stderr)
    report = Report(json.loads(stdout))
    if failed:
        raise _native.UrdfDhError(
            f"{os.fspath(out) if out is not None else 'the model'}: the written model failed its proof "
            f"(max deviation {report.written and report.written.get('max_deviation')} m); nothing was written"
        )
    return report


def _names(targets: Union[None, str, Sequence[str]]) -> List[str]:
    """Target names of a ``targets`` option (comma-separated text, or a list)."""
    if targets is None:
        return []
    if isinstance(targets, str):
        return [t.strip() for t in targets.split(",") if t.strip()]
    return list(targets)


def _as_python(lines: Sequence[str]) -> List[str]:
    """The library's warnings of predict/compensate with the CLI's ``--sequence`` named as
    this package's ``sequence=True``."""
    return [line.replace("with --sequence", "with sequence=True") for line in lines]


@contextlib.contextmanager
def _python_hint() -> Iterator[None]:
    """An error's hint with the CLI's options named as this package's arguments (``--sequence``
    as ``sequence=True``, a ``time`` column as ``time=``)."""
    try:
        yield
    except _native.UrdfDhError as e:
        hint = getattr(e, "hint", None)
        if hint:
            e.hint = hint.replace("with --sequence", "with sequence=True").replace(
                "add each row's time in seconds", "give each row's time in seconds with time= or a 'time' column"
            )
        raise


def _warn_all(lines: Sequence[str]) -> None:
    for line in lines:
        warnings.warn(line, stacklevel=3)


class Prediction:
    """The result of :func:`predict`.

    Attributes:
        targets: the target of each prediction row (``"tool"`` for tool poses).
        configs: the pose name of each row (``config``, else ``line<N>``).
        sessions: the measurement session each row was predicted in (the joint values'
            ``session`` column), or None when they had none.
        frame: the frame of the positions: ``"device"`` (the measuring device's frame of the
            calibration) or ``"base"`` (the robot's base link frame).
        points: positions, shape (rows, 3), in the length unit.
        rpy: attitudes (roll, pitch, yaw; rows x 3) in the angle unit of the tool or of 6-DoF
            targets (a calibration on orientations; NaN in point targets' rows), or None.
        uncertainty: standard uncertainties, shape (rows, 3) (positions) or (rows, 6) (with
            attitudes: then rotations about the frame's axes), or None when the model has no
            covariance.
    """

    def __init__(self, native: Tuple[Any, ...]) -> None:
        targets, configs, sessions, points, rpy, uncertainty, frame, _ = native
        self.targets: List[str] = list(targets)
        self.configs: List[str] = list(configs)
        self.sessions: Optional[List[str]] = None if sessions is None else list(sessions)
        self.frame: str = frame
        self.points: np.ndarray = np.array(points, dtype=float).reshape(-1, 3)
        self.rpy: Optional[np.ndarray] = (
            None if rpy is None else np.array(rpy, dtype=float).reshape(-1, 3)
        )
        width = 6 if rpy is not None else 3
        self.uncertainty: Optional[np.ndarray] = (
            None if uncertainty is None else np.array(uncertainty, dtype=float).reshape(-1, width)
        )

    def __repr__(self) -> str:
        u = "with" if self.uncertainty is not None else "without"
        return f"<urdf_dh.Prediction {len(self.targets)} rows, {u} uncertainty>"


def predict(
    model: PathLike,
    joints: Any,
    *,
    targets: Union[None, str, Sequence[str]] = None,
    frame: Optional[str] = None,
    session: Optional[str] = None,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    length_unit: str = "m",
    angle_unit: str = "rad",
    sequence: bool = False,
    time: Any = None,
    branch: Optional[str] = None,
) -> Prediction:
    """The calibrated model's target positions (or tool poses, ``targets="tool"``) at joint
    values, with their standard uncertainty, as ``urdf-dh predict`` computes them.

    Args:
        model: the sheet ``calibrate(..., out=...)`` wrote (or any URDF/sheet: no uncertainty).
        joints: joint values: a CSV path, a DataFrame, or an array with one column per measured
            joint of the model (``(poses, joints)``; one pose may be a 1-D array).
        frame: ``"device"`` or ``"base"`` (default: device when the model has one).
        session: with a calibration of several measurement sessions, predict every pose from
            this session's device frame (default: each row's ``session`` column of a CSV or
            DataFrame, else the first session's).
        sequence: the poses are in the order the robot moves through them (``--sequence``):
            each joint's approach direction (for a ``backlash_direction`` effect) is the sign of
            its last motion, and a ``drift`` effect reads each pose's place in the order, as
            ``calibrate`` reads a measurement file (default: unknown, the backlash added to the
            uncertainty with a warning, and no drift).
        time: each pose's time in seconds (a 1-D array, one per row; a DataFrame's ``time``
            column or a file's otherwise): a ``thermal_growth`` calibration is evaluated at
            ``t`` since the first row (the robot as at the calibration's first sample). Without
            times it is refused, naming the missing time, unless ``sequence=True`` (a
            calibration whose data had no times: the pose order).
        branch: with a calibrated tree (a tree sheet's ``calibrate(..., out=...)``), the branch
            whose targets (by default) or tool (``targets="tool"``) are predicted (``--branch``;
            default: every target on its own branch, and the tool of a tree of several branches
            needs one). The joint values hold every joint of the tree.

    Raises:
        UrdfDhError: bad model or joint values, an unknown branch or none where one is needed
            (the CLI's message).
    """
    columns = None
    if not _is_path(joints) and not _is_frame(joints):
        columns = _joints(model, base, tip)
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
    name, arrays = _source(joints, columns, "joints", points=False)
    arrays = _with_time(arrays, time, "joints", "time")
    with _python_hint():
        native = _native.predict(
            os.fspath(model),
            name,
            arrays,
            base,
            tip,
            _names(targets),
            frame,
            session,
            length_unit,
            angle_unit,
            bool(sequence),
            branch,
        )
    _warn_all(_as_python(native[-1]))
    return Prediction(native)


def compensate(
    nominal: PathLike,
    model: PathLike,
    joints: Any,
    *,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    position_only: bool = False,
    max_change: Optional[float] = None,
    length_unit: str = "m",
    angle_unit: str = "rad",
    sequence: bool = False,
    time: Any = None,
    branch: Optional[str] = None,
) -> Tuple[np.ndarray, np.ndarray, List[str]]:
    """Corrected joint values with which the calibrated ``model`` puts its tool where
    ``nominal`` puts it at the commanded ``joints`` (same forms as :func:`predict`), as
    ``urdf-dh compensate`` computes them. ``sequence`` (``--sequence``) and ``time`` (each
    pose's time in seconds, for ``thermal_growth``) as in :func:`predict`. For a calibrated
    tree, ``nominal`` is the tree sheet it started from and ``branch`` the branch whose tool is
    compensated (``--branch``; only the trunk's and that branch's joints move).

    Returns:
        ``(q, errors, failures)``: the corrected joint values (poses x joints), per pose the
        tool's position and orientation error before and after (poses x 4: position_before,
        orientation_before, position_error, orientation_error), and the report's lines naming
        each pose that could not be compensated (empty when all were).

    Raises:
        UrdfDhError: bad models or joint values (the CLI's message).
    """
    columns = _joints(model, None, None)
    if not _is_path(joints) and not _is_frame(joints):
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
    name, arrays = _source(joints, columns, "joints", points=False)
    arrays = _with_time(arrays, time, "joints", "time")
    with _python_hint():
        q, errors, failures, notes = _native.compensate(
            os.fspath(nominal),
            os.fspath(model),
            name,
            arrays,
            base,
            tip,
            position_only,
            None if max_change is None else repr(float(max_change)),
            length_unit,
            angle_unit,
            bool(sequence),
            branch,
        )
    _warn_all(_as_python(notes))
    return (
        np.array(q, dtype=float).reshape(-1, len(columns)),
        np.array(errors, dtype=float).reshape(-1, 4),
        list(failures),
    )
