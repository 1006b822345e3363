"""Type stubs of the Rust extension ``urdf_dh._native`` (use the ``urdf_dh`` package instead)."""

from typing import List, Optional, Tuple

Matrix = List[List[float]]
RowTuple = Tuple[
    str, str, float, float, float, float, Optional[float], Optional[float],
    Optional[Tuple[str, float, float]],
]

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
    def fk(self, q: List[float]) -> Matrix: ...

def extract(
    source: str,
    is_xml: bool,
    base: Optional[str],
    tip: Optional[str],
    convention_name: str,
    samples: int,
    seed: int,
    linear: float,
    angular: float,
) -> NativeTable: ...
def check(
    source: str,
    is_xml: bool,
    sheet: str,
    base: Optional[str],
    tip: Optional[str],
    linear: float = ...,
    angular: float = ...,
) -> str: ...
def run(argv: List[str]) -> Tuple[str, str, bool]: ...
def measured_joints(model: str, base: Optional[str] = None, tip: Optional[str] = None) -> List[str]: ...
