"""Simulated measurements of a model with planted errors and effects: ``simulate``.

It calls the ``urdf-dh`` library's simulator in process (the Rust extension), so the data, the
truth and the checks on the options are ``urdf-dh simulate``'s own. Units: metres and radians.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple, Union

from . import _native
from .calibration import PathLike, _warn


@dataclass(frozen=True)
class Simulation:
    """A simulated measurement set and its truth.

    Attributes:
        csv: the measurement CSV as ``urdf-dh simulate`` writes it (a ``#`` comment line, then the
            canonical columns: joints, x, y, z, target, config, sigma, ...), in metres and radians.
        truth: the true model as a dict: a DH sheet (metres, radians) with a ``truth`` section
            (device frame, targets, planted errors and effects, noise, seed).
        truth_yaml: the truth as the YAML file ``urdf-dh simulate`` writes.
        model: the model's path (never overwritten by :meth:`write`).
    """

    csv: str
    truth: Dict[str, Any]
    truth_yaml: str
    model: str = ""

    def frame(self) -> Any:
        """The measurements as a pandas ``DataFrame`` (the CSV's columns), ready for
        :func:`urdf_dh.calibrate`."""
        import io

        import pandas as pd

        return pd.read_csv(io.StringIO(self.csv), comment="#")

    def write(self, path: PathLike, truth: Optional[PathLike] = None) -> Tuple[str, str]:
        """Writes the CSV to ``path`` and the truth to ``truth`` (default: beside it,
        ``<stem>.truth.yaml``); returns both paths. As the command line writes: both files or
        neither, never over the model or each other.

        Raises:
            UrdfDhError: a path that is the model or the other file, or a missing folder.
        """
        path = os.fspath(path)
        if truth is None:
            stem = os.path.splitext(os.path.basename(path))[0] or "data"
            truth = os.path.join(os.path.dirname(path), f"{stem}.truth.yaml")
        truth = os.fspath(truth)
        inputs = [("model", self.model)] if self.model else []
        _native.write_outputs(inputs, [("path", path, self.csv), ("truth", truth, self.truth_yaml)])
        return path, truth


def _assignments(values: Union[None, Mapping[str, Any], Sequence[str]], what: str) -> list:
    """``{"name": value}`` (a value or a sequence of values) or ``["name=value"]`` as the CLI's
    ``NAME=VALUE[,VALUE...]`` strings."""
    if values is None:
        return []
    if isinstance(values, Mapping):
        out = []
        for name, v in values.items():
            vs = v if isinstance(v, (list, tuple)) else [v]
            out.append(f"{name}=" + ",".join(repr(float(x)) for x in vs))
        return out
    if isinstance(values, str):
        raise TypeError(f"{what}: expected a dict or a list of 'NAME=VALUE' strings, found a str")
    return [str(v) for v in values]


def simulate(
    model: PathLike,
    *,
    poses: int = 100,
    noise: float = 0.0,
    errors: Union[None, Mapping[str, float], Sequence[str]] = None,
    effects: Union[None, Mapping[str, Any], Sequence[str]] = None,
    random_errors: Optional[Tuple[float, float]] = None,
    targets: int = 1,
    repeats: int = 1,
    validation: float = 0.0,
    sessions: int = 1,
    seed: int = 1,
    cpa: bool = False,
    arc: Optional[float] = None,
    orientation_noise: Optional[float] = None,
    gravity: Optional[Sequence[float]] = None,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    name: str = "simulated.csv",
) -> Simulation:
    """Simulates measurements of ``model`` (a URDF or DH sheet path) with planted errors, as
    ``urdf-dh simulate`` does.

    Args:
        poses: random poses (with ``cpa``, poses per joint sweep).
        noise: standard deviation of the measurement noise per axis, metres.
        errors: geometric errors by parameter name, metres and radians
            (``{"elbow_joint.theta": 1e-3}``); or ``random_errors=(length, angle)`` on every
            DH parameter.
        effects: effects by label, each a value or a list of values
            (``{"gear_ratio:elbow_joint": 1e-3}``, ``{"gear_harmonic:wrist_1_joint": [1e-4, 0.3]}``).
        targets, repeats, validation, sessions, seed: as ``urdf-dh simulate``'s options.
        cpa: sweep one joint at a time (circle-point analysis data), each by ``arc`` radians.
        orientation_noise: a 6-DoF device: noise of each orientation per axis, radians.
        gravity: ``(x, y, z)``, m/s² in the robot's base link frame (default ``(0, 0, -9.80665)``):
            the direction of a planted ``gravity_sag:J``, as ``urdf-dh simulate --gravity``.
        name: the data's name in the truth (and the truth's, ``<stem>.truth.yaml``, in the CSV).

    Raises:
        UrdfDhError: a bad model, option, error or effect (the CLI's message and ``.hint``).
    """
    stem = os.path.splitext(os.path.basename(name))[0] or "data"
    csv, truth_json, truth_yaml, stderr = _native.simulate(
        os.fspath(model),
        base,
        tip,
        str(int(poses)),
        repr(float(noise)),
        None if orientation_noise is None else repr(float(orientation_noise)),
        bool(cpa),
        None if arc is None else repr(float(arc)),
        _assignments(effects, "effects"),
        _assignments(errors, "errors"),
        None if random_errors is None else ",".join(repr(float(v)) for v in random_errors),
        str(int(targets)),
        str(int(repeats)),
        repr(float(validation)),
        str(int(sessions)),
        int(seed),
        name,
        f"{stem}.truth.yaml",
        None if gravity is None else [repr(float(v)) for v in gravity],
    )
    _warn(stderr)
    return Simulation(csv=csv, truth=json.loads(truth_json), truth_yaml=truth_yaml, model=os.fspath(model))
