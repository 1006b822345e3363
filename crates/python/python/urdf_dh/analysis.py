"""Circle-point analysis: ``cpa``, the joint axes and DH table of measurements in which one joint
moves at a time, as ``urdf-dh cpa`` computes them (the Rust extension, in process).

Measurements may be a file path or a pandas ``DataFrame`` (the measurement CSV's columns by name,
as for :func:`urdf_dh.calibrate`; without a model every other numeric column is a joint). Units
are those of ``length_unit`` and ``angle_unit``; every result is in metres and radians.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Optional

from . import _native
from .calibration import PathLike, _joints, _source, _warn


@dataclass(frozen=True)
class CpaResult:
    """A circle-point analysis.

    Attributes:
        sheet: the extracted DH table as a sheet dict (metres, radians; ``base_link: device``:
            the base is in the measuring device's frame), with the report as its ``cpa`` section
            (sweeps, circles, measured against commanded motion, the comparison with a model).
        yaml: the same as ``urdf-dh cpa --format yaml`` prints it.
    """

    sheet: Dict[str, Any]
    yaml: str

    @property
    def report(self) -> Dict[str, Any]:
        """The ``cpa`` section: ``sweeps``, ``joints`` (each axis line and its motion fit),
        ``pairs`` (against the model), ``proof``."""
        return self.sheet["cpa"]

    @property
    def rows(self) -> List[Dict[str, Any]]:
        """The DH rows (``name``, ``type``, ``a``, ``alpha``, ``d``, ``theta``, ...)."""
        return self.sheet["joints"]


def cpa(
    data: Any,
    model: Optional[PathLike] = None,
    *,
    base: Optional[str] = None,
    tip: Optional[str] = None,
    convention: str = "standard",
    linear_tol: Optional[float] = None,
    angular_tol: Optional[float] = None,
    length_unit: str = "m",
    angle_unit: str = "rad",
) -> CpaResult:
    """The circle-point analysis of ``data`` (a CSV path or a DataFrame), as ``urdf-dh cpa``:
    ``model`` (a URDF or sheet path) names the joints and kinds and is compared with the
    measured axes; without it the data's joint columns are revolute joints in ``convention``.
    ``linear_tol`` (m) and ``angular_tol`` (rad) are the extraction's tolerances (default 0.1 mm
    and 1 mrad, ``CPA_LINEAR``, ``CPA_ANGULAR``).

    Raises:
        FileNotFoundError: a file does not exist.
        UrdfDhError: bad data or model, a joint without a sweep (the CLI's message and hint).
    """
    columns = None
    if model is not None and not isinstance(data, (str, os.PathLike)) and not hasattr(data, "columns"):
        columns = _joints(model, base, tip)
    data_name, arrays = _source(data, columns, "data", points=True, strict=model is None)
    sheet, yaml, stderr = _native.cpa(
        data_name,
        arrays,
        None if model is None else os.fspath(model),
        base,
        tip,
        convention,
        float(_native.CPA_LINEAR if linear_tol is None else linear_tol),
        float(_native.CPA_ANGULAR if angular_tol is None else angular_tol),
        length_unit,
        angle_unit,
    )
    _warn(stderr)
    return CpaResult(sheet=json.loads(sheet), yaml=yaml)
