"""Calibration from measured points, and using its result: ``calibrate``, ``predict``,
``compensate``.

Each runs the ``urdf-dh`` command of the same name in process (the Rust extension), so the
results, the checks on the input and the messages are the command line's own. Measurements may
be a file path, a pandas ``DataFrame`` (columns named as in the measurement CSV: one per joint,
``x``, ``y``, ``z``, optional ``target``, ``config``, ``sigma``, ``set``...) or a numpy array
(one column per measured joint of the model in its order, then ``x``, ``y``, ``z``); a
DataFrame or an array is handed over as the same CSV text, in a temporary file. Units are those
of the options (``length_unit``, ``angle_unit``); every report is in metres and radians.
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
import warnings
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

PathLike = Union[str, "os.PathLike[str]"]


def _warn(stderr: str) -> None:
    for line in stderr.splitlines():
        if line.startswith("urdf-dh: warning: "):
            warnings.warn(line[len("urdf-dh: warning: ") :], stacklevel=3)


def _csv_text(table: Any, columns: Optional[Sequence[str]], what: str) -> str:
    """CSV text of a DataFrame (its own columns) or a 2-D array (``columns``)."""
    if hasattr(table, "to_csv") and hasattr(table, "columns"):
        return str(table.to_csv(index=False, float_format="%.17g"))
    array = np.asarray(table, dtype=float)
    if array.ndim != 2:
        raise ValueError(f"{what}: expected a 2-D array (one row per sample), found shape {array.shape}")
    if columns is None or array.shape[1] != len(columns):
        raise ValueError(
            f"{what}: expected {len(columns or [])} columns ({', '.join(columns or [])}), "
            f"found {array.shape[1]}"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{what}: expected finite numbers, found NaN or inf")
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for row in array:
        writer.writerow([repr(float(v)) for v in row])
    return out.getvalue()


class _Files:
    """Temporary files for in-memory inputs, removed on exit."""

    def __init__(self) -> None:
        self._dir = tempfile.TemporaryDirectory(prefix="urdf_dh_")

    def __enter__(self) -> "_Files":
        return self

    def __exit__(self, *exc: Any) -> None:
        self._dir.cleanup()

    def path(self, data: Any, name: str, columns: Optional[Sequence[str]], what: str) -> str:
        if isinstance(data, (str, os.PathLike)):
            return os.fspath(data)
        path = os.path.join(self._dir.name, name)
        with open(path, "w", encoding="utf-8") as f:
            f.write(_csv_text(data, columns, what))
        return path


def _joints(model: PathLike, base: Optional[str], tip: Optional[str]) -> List[str]:
    return list(_native.measured_joints(os.fspath(model), base, tip))


def _chain(base: Optional[str], tip: Optional[str]) -> List[str]:
    argv: List[str] = []
    if base is not None:
        argv += ["--base", base]
    if tip is not None:
        argv += ["--tip", tip]
    return argv


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
            ``std_error``, ``free``).
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
    targets: Optional[Sequence[str]] = None,
    sigma: Optional[float] = None,
    folds: Optional[int] = None,
    keep_outliers: bool = False,
    inertials: Optional[PathLike] = None,
    length_unit: str = "m",
    angle_unit: str = "rad",
    out: Optional[PathLike] = None,
) -> Report:
    """Fits ``model`` (a URDF or DH sheet path; None: start from circle-point analysis) to
    measured points, as ``urdf-dh calibrate`` does.

    Args:
        data: measurements: a CSV path, a pandas DataFrame, or a numpy array (the model's
            measured joints, then x, y, z).
        validate: validation measurements, same forms.
        effects: None, ``"auto"``, or effect labels (``["gear_ratio:elbow_joint"]``).
        out: write the calibrated model there (a sheet, or a URDF for ``.urdf``), proved as
            written; :func:`predict` and :func:`compensate` read it.
        The other options are the CLI's (``--sigma`` in ``length_unit``, ...).

    Raises:
        FileNotFoundError: a file does not exist.
        UrdfDhError: bad model or data (the CLI's message and ``.hint``), or a written model
            that failed its proof.
    """
    columns = None
    if model is not None and not isinstance(data, (str, os.PathLike)) and not hasattr(data, "columns"):
        columns = _joints(model, base, tip) + ["x", "y", "z"]
    with _Files() as files:
        argv = ["calibrate", "--data", files.path(data, "data.csv", columns, "data")]
        if model is not None:
            argv += ["--model", os.fspath(model)] + _chain(base, tip)
        if validate is not None:
            argv += ["--validate", files.path(validate, "validate.csv", columns, "validate")]
        if effects is not None:
            argv += ["--effects", effects if isinstance(effects, str) else ",".join(effects)]
        if max_effects is not None:
            argv += ["--max-effects", str(int(max_effects))]
        if targets:
            argv += ["--targets", ",".join(targets)]
        if sigma is not None:
            argv += ["--sigma", repr(float(sigma))]
        if folds is not None:
            argv += ["--folds", str(int(folds))]
        if keep_outliers:
            argv.append("--keep-outliers")
        if inertials is not None:
            argv += ["--inertials", os.fspath(inertials)]
        if out is not None:
            argv += ["--out", os.fspath(out)]
        argv += ["--length-unit", length_unit, "--angle-unit", angle_unit, "--format", "json", "--quiet"]
        stdout, stderr, failed = _native.run(argv)
    _warn(stderr)
    report = Report(json.loads(stdout))
    if failed:
        raise _native.UrdfDhError(
            f"{os.fspath(out) if out is not None else 'the model'}: the written model failed its proof "
            f"(max deviation {report.written and report.written.get('max_deviation')} m); nothing was written"
        )
    return report


def _rows(text: str) -> Iterator[Dict[str, str]]:
    return csv.DictReader(line for line in text.splitlines() if not line.startswith("#"))


class Prediction:
    """The result of :func:`predict`.

    Attributes:
        targets: the target of each prediction row (``"tool"`` for tool poses).
        configs: the pose name of each row (``config``, else ``line<N>``).
        sessions: the measurement session each row was predicted in (the joint values'
            ``session`` column), or None when they had none.
        points: positions, shape (rows, 3), in the length unit.
        rpy: tool attitudes (roll, pitch, yaw; rows x 3) in the angle unit, or None.
        uncertainty: standard uncertainties, shape (rows, 3) (positions) or (rows, 6) (tool: then
            rotations about the frame's axes), or None when the model has no covariance.
    """

    def __init__(self, text: str) -> None:
        rows = list(_rows(text))
        tool = bool(rows) and "roll" in rows[0]
        self.targets: List[str] = [r["target"] for r in rows]
        self.configs: List[str] = [r["config"] for r in rows]
        self.sessions: Optional[List[str]] = (
            [r["session"] for r in rows] if rows and "session" in rows[0] else None
        )
        self.points: np.ndarray = np.array([[float(r[k]) for k in "xyz"] for r in rows]).reshape(-1, 3)
        self.rpy: Optional[np.ndarray] = (
            np.array([[float(r[k]) for k in ("roll", "pitch", "yaw")] for r in rows]).reshape(-1, 3)
            if tool
            else None
        )
        keys = ["u_x", "u_y", "u_z"] + (["u_rx", "u_ry", "u_rz"] if tool else [])
        self.uncertainty: Optional[np.ndarray] = (
            np.array([[float(r[k]) for k in keys] for r in rows]).reshape(-1, len(keys))
            if rows and "u_x" in rows[0]
            else None
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

    Raises:
        UrdfDhError: bad model or joint values (the CLI's message).
    """
    columns = None
    if not isinstance(joints, (str, os.PathLike)) and not hasattr(joints, "columns"):
        columns = _joints(model, base, tip)
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
    with _Files() as files:
        argv = ["predict", "--model", os.fspath(model), "--joints", files.path(joints, "q.csv", columns, "joints")]
        argv += _chain(base, tip)
        if targets is not None:
            argv += ["--targets", targets if isinstance(targets, str) else ",".join(targets)]
        if frame is not None:
            argv += ["--frame", frame]
        if session is not None:
            argv += ["--session", session]
        argv += ["--length-unit", length_unit, "--angle-unit", angle_unit]
        stdout, stderr, _ = _native.run(argv)
    _warn(stderr)
    return Prediction(stdout)


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
) -> Tuple[np.ndarray, np.ndarray, List[str]]:
    """Corrected joint values with which the calibrated ``model`` puts its tool where
    ``nominal`` puts it at the commanded ``joints`` (same forms as :func:`predict`), as
    ``urdf-dh compensate`` computes them.

    Returns:
        ``(q, errors, failures)``: the corrected joint values (poses x joints), per pose the
        tool's position and orientation error before and after (poses x 4: position_before,
        orientation_before, position_error, orientation_error), and the report's lines naming
        each pose that could not be compensated (empty when all were).

    Raises:
        UrdfDhError: bad models or joint values (the CLI's message).
    """
    columns = _joints(model, None, None)
    if not isinstance(joints, (str, os.PathLike)) and not hasattr(joints, "columns"):
        joints = np.atleast_2d(np.asarray(joints, dtype=float))
    with _Files() as files:
        argv = [
            "compensate", "--nominal", os.fspath(nominal), "--model", os.fspath(model),
            "--joints", files.path(joints, "q.csv", columns, "joints"),
        ] + _chain(base, tip)
        if position_only:
            argv.append("--position-only")
        if max_change is not None:
            argv += ["--max-change", repr(float(max_change))]
        argv += ["--length-unit", length_unit, "--angle-unit", angle_unit]
        stdout, stderr, _ = _native.run(argv)
    _warn(stderr)
    rows = list(_rows(stdout))
    q = np.array([[float(r[c]) for c in columns] for r in rows]).reshape(-1, len(columns))
    keys = ["position_before", "orientation_before", "position_error", "orientation_error"]
    errors = np.array([[float(r[k]) for k in keys] for r in rows]).reshape(-1, 4)
    failures = [line.strip() for line in stderr.splitlines() if line.startswith("  ")]
    return q, errors, failures
