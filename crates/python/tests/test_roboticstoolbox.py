"""Table.to_roboticstoolbox: the DHRobot's FK equals the table's (verified against the URDF) on
every robot of ../shared/robots, both conventions, at random joint values, to 1e-9."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import urdf_dh
from conftest import PANDA, SHARED

ROBOTS = SHARED / "robots"
FK_TOL = 1e-9  # metres / unit-matrix entries: double-precision products of ~10 transforms


def rtb_or_skip():
    try:
        import roboticstoolbox  # noqa: F401
    except ImportError as e:  # pragma: no cover - depends on the machine
        print(f"skipping: roboticstoolbox-python is not importable ({e})")
        pytest.skip(f"roboticstoolbox-python is not importable ({e})")


def longest_chain(urdf_path):
    """(root link, leaf link) of the root-to-leaf path with the most moving joints."""
    root = ET.parse(urdf_path).getroot()
    parent_of = {}  # child link -> (parent link, moving?)
    for j in root.findall("joint"):
        parent_of[j.find("child").get("link")] = (
            j.find("parent").get("link"),
            j.get("type") not in ("fixed", "floating", "planar"),
        )
    links = [l.get("name") for l in root.findall("link")]
    parents = {p for p, _ in parent_of.values()}
    best = None
    for leaf in links:
        if leaf in parents:
            continue
        n, link = 0, leaf
        while link in parent_of:
            link, moving = parent_of[link]
            n += moving
        if best is None or n > best[0]:
            best = (n, link, leaf)
    return best[1], best[2]


def robot_dirs():
    if not ROBOTS.is_dir():
        return []
    return sorted(p for p in ROBOTS.iterdir() if (p / "robot.urdf").exists())


def check_robot(urdf, base, tip, seed):
    rng = np.random.default_rng(seed)
    for convention in ("standard", "modified"):
        t = urdf_dh.extract(urdf, base=base, tip=tip, convention=convention)
        assert t.verification["passed"], (urdf, t.verification)
        robot = t.to_roboticstoolbox()
        assert robot.n == len(t.rows)
        for r, link in zip(t.rows, robot.links):
            if r.lower is not None:
                np.testing.assert_array_equal(link.qlim, [r.lower, r.upper])
        for _ in range(5):
            q = rng.uniform(-np.pi, np.pi, len(t.rows))
            expected = t.fk(q)
            got = robot.fkine(q).A
            np.testing.assert_allclose(got, expected, rtol=0, atol=FK_TOL, err_msg=str(urdf))


def test_panda_fixture():
    rtb_or_skip()
    check_robot(PANDA, None, None, 1)


def test_every_shared_robot():
    rtb_or_skip()
    dirs = robot_dirs()
    if not dirs:
        print(f"skipping: {ROBOTS} is absent (the shared corpus sits beside the repository)")
        pytest.skip(f"{ROBOTS} is absent")
    assert len(dirs) >= 50
    for i, d in enumerate(dirs):
        base, tip = longest_chain(d / "robot.urdf")
        check_robot(d / "robot.urdf", base, tip, i)


def test_missing_roboticstoolbox_is_a_clear_import_error(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_rtb(name, *args, **kwargs):
        if name.split(".")[0] in ("roboticstoolbox", "spatialmath"):
            raise ImportError(f"No module named '{name}'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_rtb)
    t = urdf_dh.extract(PANDA)
    with pytest.raises(ImportError, match="pip install roboticstoolbox-python"):
        t.to_roboticstoolbox()
