"""Denavit-Hartenberg parameters of serial manipulators from URDF, verified.

The computations are the ``urdf-dh`` command line's own (a Rust extension, ``urdf_dh._native``);
this module turns their results into numpy arrays and small Python objects. Units are SI:
metres and radians. Poses are 4x4 homogeneous matrices (numpy ``float64``).

>>> import urdf_dh
>>> table = urdf_dh.extract("robot.urdf")          # doctest: +SKIP
>>> table.fk([0.0] * len(table.rows))               # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import UrdfDhError
from .analysis import CpaResult, cpa
from .calibration import Prediction, Report, calibrate, compensate, predict
from .simulation import Simulation, simulate

__all__ = [
    "CheckReport",
    "CpaResult",
    "Mimic",
    "Prediction",
    "Report",
    "Row",
    "Simulation",
    "Table",
    "UrdfDhError",
    "VerificationFailed",
    "calibrate",
    "check",
    "compensate",
    "cpa",
    "extract",
    "predict",
    "simulate",
]

UrdfSource = Union[str, "os.PathLike[str]"]

UrdfDhError.hint = None  # class default; instances carry the CLI's `hint:` line when it has one


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another: ``q = multiplier * q_driver + offset`` (URDF ``<mimic>``)."""

    joint: str
    multiplier: float
    offset: float


@dataclass(frozen=True)
class Row:
    """One DH row: joint ``name``, ``type`` (``"revolute"``/``"prismatic"``), ``a`` and ``d``
    (metres), ``alpha`` and ``theta`` (radians), joint limits ``lower``/``upper`` in the joint's
    unit (``None`` for a continuous joint) and ``mimic`` (``None`` unless the joint follows
    another). The joint value adds to ``theta`` (revolute) or ``d`` (prismatic)."""

    name: str
    type: str
    a: float
    alpha: float
    d: float
    theta: float
    lower: Optional[float]
    upper: Optional[float]
    mimic: Optional[Mimic]


def _xacro(
    xacro_args: Optional[Mapping[str, Any]], packages: Optional[Mapping[str, Any]]
) -> "tuple[Optional[List[Tuple[str, str]]], Optional[List[Tuple[str, str]]]]":
    """The ``xacro_args`` / ``packages`` keywords as the native functions take them: a bool
    argument is written ``true``/``false`` (as xacro reads it), anything else as ``str()``."""

    def text(v: Any) -> str:
        return ("true" if v else "false") if isinstance(v, bool) else str(v)

    args = None if xacro_args is None else [(str(k), text(v)) for k, v in xacro_args.items()]
    pkgs = None if packages is None else [(str(k), os.fspath(v)) for k, v in packages.items()]
    return args, pkgs


def _source(path_or_xml: UrdfSource) -> "tuple[str, bool]":
    if isinstance(path_or_xml, str) and path_or_xml.lstrip().startswith("<"):
        return path_or_xml, True
    if isinstance(path_or_xml, (bytes, bytearray)):
        raise TypeError("expected a path or URDF text (str), found bytes: decode them first")
    return os.fspath(path_or_xml), False


class Table:
    """A DH table extracted from a URDF chain, with its verification.

    Attributes:
        rows: one :class:`Row` per moving joint, base to tip.
        base: DH frame 0 in the base link frame (4x4).
        tool: the tip link frame in the last DH frame (4x4).
        convention: ``"standard"`` or ``"modified"``.
        verification: the forward-kinematics proof of the YAML sheet as written
            (``samples``, ``seed``, ``max_position_error`` (m), ``max_orientation_error`` (rad),
            ``position_bound``, ``orientation_bound``, ``passed``).
        warnings: the extraction's warnings (what ``urdf-dh extract`` prints as warnings).
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        self.rows: List[Row] = [
            Row(n, k, a, al, d, th, lo, up, None if m is None else Mimic(*m))
            for (n, k, a, al, d, th, lo, up, m) in native.rows()
        ]
        self.base: np.ndarray = np.array(native.base())
        self.tool: np.ndarray = np.array(native.tool())
        self.convention: str = native.convention()
        self.verification: Dict[str, Any] = json.loads(native.verification_json())
        self.warnings: List[str] = native.warnings()

    def __repr__(self) -> str:
        names = ", ".join(r.name for r in self.rows)
        passed = "passed" if self.verification.get("passed") else "FAILED"
        return f"<urdf_dh.Table {self.convention}, {len(self.rows)} rows ({names}), verification {passed}>"

    def fk(self, q: Union[Sequence[float], np.ndarray]) -> np.ndarray:
        """The tip link in the base link frame (4x4) at joint values ``q``, one per row
        (radians for revolute, metres for prismatic rows).

        Raises:
            UrdfDhError: ``q`` does not have one value per row, holds a value that is not a
                finite real number within ``urdf-dh extract --q``'s range ([-100, 100]), or is
                complex (its imaginary part would be dropped).
        """
        values = _real_values(q, "fk: q").tolist()
        return np.array(self._native.fk(values))

    def to_yaml(self) -> str:
        """The YAML sheet ``urdf-dh extract --format yaml`` writes (verification included)."""
        return str(self._native.yaml())

    def to_dict(self) -> Dict[str, Any]:
        """The same sheet as a dict (the keys of ``urdf-dh extract --format json``)."""
        return dict(json.loads(self._native.sheet_json()))

    def to_poe(self) -> Dict[str, Any]:
        """The table's product-of-exponentials form (Lynch & Park, *Modern Robotics*, eq. 4.14,
        the space form): ``fk(q) = expm([S_1] q_1) @ ... @ expm([S_n] q_n) @ M``.

        Returns a dict with ``screws`` (n x 6 array: each row ``(omega, v)``, the joint's unit
        screw axis in the base link frame at zero; ``v = -omega x p`` for a point ``p`` of a
        revolute axis, ``omega = 0`` and ``v`` the unit direction for a prismatic one), ``M``
        (4x4, the tip link at zero), ``names`` and ``types`` (one per row). The same form as
        ``urdf-dh extract --format poe``, here from the table itself, at full precision.
        """
        doc = json.loads(self._native.poe_json())
        joints = doc["joints"]
        return {
            "screws": np.array([j["screw"] for j in joints], dtype=float).reshape(-1, 6),
            "M": np.array(doc["home"], dtype=float),
            "names": [j["name"] for j in joints],
            "types": [j["type"] for j in joints],
        }

    def to_roboticstoolbox(self) -> Any:
        """The table as a Robotics Toolbox ``DHRobot`` (needs ``roboticstoolbox-python``).

        Links are ``RevoluteDH``/``PrismaticDH`` (standard) or ``RevoluteMDH``/``PrismaticMDH``
        (modified) with ``theta`` (revolute) or ``d`` (prismatic) as the joint offset and the
        limits as ``qlim``; ``base`` and ``tool`` are the table's, so ``robot.fkine(q).A`` equals
        :meth:`fk`.

        Raises:
            ImportError: roboticstoolbox-python is not installed.
        """
        try:
            import roboticstoolbox as rtb
            from spatialmath import SE3
        except ImportError as e:
            raise ImportError(
                "Table.to_roboticstoolbox needs roboticstoolbox-python: "
                "pip install roboticstoolbox-python"
            ) from e
        standard = self.convention == "standard"
        revolute = rtb.RevoluteDH if standard else rtb.RevoluteMDH
        prismatic = rtb.PrismaticDH if standard else rtb.PrismaticMDH
        links = []
        for r in self.rows:
            qlim = None if r.lower is None else [r.lower, r.upper]
            if r.type == "revolute":
                link = revolute(d=r.d, a=r.a, alpha=r.alpha, offset=r.theta, qlim=qlim)
            else:
                link = prismatic(theta=r.theta, a=r.a, alpha=r.alpha, offset=r.d, qlim=qlim)
            link.name = r.name
            links.append(link)
        name = self.to_dict().get("robot") or "robot"
        return rtb.DHRobot(
            links,
            name=name,
            base=SE3(self.base, check=False),
            tool=SE3(self.tool, check=False),
        )


def _real_values(values: Any, what: str) -> np.ndarray:
    """``values`` as a flat float64 array; complex values are refused rather than cut to their
    real part (numpy's ``astype(float)`` drops the imaginary part with only a warning)."""
    array = np.asarray(values)
    if np.iscomplexobj(array):
        raise UrdfDhError(f"{what}: expected real numbers, found complex values (dtype {array.dtype})")
    try:
        return np.asarray(array, dtype=float).reshape(-1)
    except (TypeError, ValueError) as e:
        raise UrdfDhError(f"{what}: expected numbers, found {array.dtype} values: {e}") from None


def _count(value: Any) -> str:
    """An integer argument as the text the command line's range parser reads (``1.5`` or
    ``True`` stay visibly what they are, and are refused there)."""
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        return str(int(value))
    return repr(value)


def _number(value: Any, what: str) -> str:
    """A float argument as the text the command line's range parser reads (``5`` as ``5``,
    as the CLI echoes it); a complex or non-numeric value is refused with the argument named."""
    if isinstance(value, (complex, np.complexfloating)):
        raise UrdfDhError(f"{what}: expected a real number, found {value!r}")
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise UrdfDhError(f"{what}: expected a number, found {value!r}")
    return repr(value.item() if isinstance(value, (np.integer, np.floating)) else value)


class VerificationFailed(UrdfDhError):  # type: ignore[misc, valid-type]
    """The extracted table, written as YAML and read back, strays from the URDF beyond its
    bound (``urdf-dh extract`` prints the table and exits 1). The message is the CLI's error
    line; ``.table`` holds the :class:`Table` (with ``verification["passed"]`` False) for
    inspection."""

    table: "Table"


def extract(
    path_or_xml: UrdfSource,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    convention: str = "standard",
    samples: int = 1000,
    seed: int = 0,
    linear_tolerance: float = _native.DEFAULT_LINEAR,
    angular_tolerance: float = _native.DEFAULT_ANGULAR,
    xacro_args: Optional[Mapping[str, Any]] = None,
    packages: Optional[Mapping[str, Any]] = None,
) -> Table:
    """Extracts the DH table of a URDF chain, as ``urdf-dh extract`` does.

    Args:
        path_or_xml: a path (str or os.PathLike; a ``.xacro`` file is expanded natively, without
            Python's ``xacro``; an MJCF file, recognised by its ``<mujoco>`` root, with its
            ``<include>`` files beside it), or URDF or MJCF XML text (a string starting with ``<``
            after whitespace).
        base: base link (default: the root link).
        tip: tip link (default: the only leaf).
        convention: ``"standard"`` or ``"modified"``.
        samples: random joint-value samples of the verification, in [1, 1000000] (a chain of
            more than 10 joints: at most 1e7 joint evaluations in all), as ``--samples``.
        seed: seed of the sampler.
        linear_tolerance: metres, for the axis classification.
        angular_tolerance: radians, likewise.
        xacro_args: arguments of a ``.xacro`` file, ``{"name": value}`` (``--xacro-arg
            name:=value``).
        packages: package folders for ``$(find NAME)``, ``{"NAME": path}`` (``--package
            NAME=DIR``), searched before ROS_PACKAGE_PATH and AMENT_PREFIX_PATH.

    The table written as YAML is read back and its forward kinematics compared with the URDF's;
    ``Table.verification`` holds the figures. A table that strays beyond the bound is not
    returned: :class:`VerificationFailed` is raised (the CLI exits 1), carrying it as ``.table``.

    Raises:
        FileNotFoundError: the file does not exist.
        UrdfDhError: invalid URDF, unknown or ambiguous base/tip, a chain without moving joints,
            an argument outside the CLI's range (``samples``, the tolerances: the CLI's message;
            ``.hint`` its hint).
        VerificationFailed: the verification failed (a subclass of UrdfDhError).
    """
    source, is_xml = _source(path_or_xml)
    args, pkgs = _xacro(xacro_args, packages)
    native = _native.extract(
        source,
        is_xml,
        base,
        tip,
        convention,
        _count(samples),
        _count(seed),
        _number(linear_tolerance, "linear_tolerance"),
        _number(angular_tolerance, "angular_tolerance"),
        args,
        pkgs,
    )
    table = Table(native)
    failure = native.failure()
    if failure is not None:
        error = VerificationFailed(failure)
        error.table = table
        raise error
    return table


class CheckReport:
    """The report of :func:`check` (the JSON of ``urdf-dh check --format json``).

    Attributes:
        matches: no difference found.
        verdict: ``"match"`` or ``"mismatch"``.
        differences: one dict per difference (``joint``, ``parameter``, ``urdf``, ``sheet``,
            ``difference``, ``note``; SI units).
        max_position_error: metres (sheet taken literally, base/tool fitted), or None.
        max_orientation_error: radians, or None.
        warnings: remarks (joint names that differ, suspicious units).
    """

    def __init__(self, report: Dict[str, Any]) -> None:
        self._report = report
        self.matches: bool = bool(report["matches"])
        self.verdict: str = "match" if self.matches else "mismatch"
        self.differences: List[Dict[str, Any]] = list(report["differences"])
        self.max_position_error: Optional[float] = report.get("max_position_error")
        self.max_orientation_error: Optional[float] = report.get("max_orientation_error")
        self.warnings: List[str] = list(report.get("warnings", []))

    def __repr__(self) -> str:
        return f"<urdf_dh.CheckReport {self.verdict}, {len(self.differences)} differences>"

    def to_dict(self) -> Dict[str, Any]:
        """The report as ``urdf-dh check --format json`` prints it."""
        return json.loads(json.dumps(self._report))


def check(
    urdf: UrdfSource,
    sheet: Union[str, "os.PathLike[str]"],
    base: Optional[str] = None,
    tip: Optional[str] = None,
    linear_tolerance: float = _native.CHECK_LINEAR,
    angular_tolerance: float = _native.CHECK_ANGULAR,
    xacro_args: Optional[Mapping[str, Any]] = None,
    packages: Optional[Mapping[str, Any]] = None,
) -> CheckReport:
    """Compares a URDF chain with a vendor DH sheet (a YAML/JSON sheet file), as
    ``urdf-dh check`` does: names every joint and parameter that differs. ``xacro_args`` and
    ``packages`` are those of :func:`extract`, for a ``.xacro`` robot.

    Raises:
        FileNotFoundError: a file does not exist.
        UrdfDhError: invalid URDF or sheet (the CLI's message).
    """
    source, is_xml = _source(urdf)
    args, pkgs = _xacro(xacro_args, packages)
    text = _native.check(
        source,
        is_xml,
        os.fspath(sheet),
        base,
        tip,
        _number(linear_tolerance, "linear_tolerance"),
        _number(angular_tolerance, "angular_tolerance"),
        args,
        pkgs,
    )
    return CheckReport(json.loads(text))
