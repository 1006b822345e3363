"""Shared paths of the urdf_dh tests."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
FIXTURES = REPO / "fixtures"
SHARED = REPO.parent / "shared"
PANDA = FIXTURES / "robots" / "franka_panda" / "robot.urdf"
