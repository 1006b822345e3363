"""urdf_dh.cpa: the command line's circle-point analysis, from a file or a DataFrame."""

import pytest

import urdf_dh
from urdf_dh import _native
from conftest import FIXTURES

UR5 = FIXTURES / "robots" / "ur5" / "vendor.yaml"


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    """A UR5 swept one joint at a time with a planted error (``urdf-dh simulate --cpa``)."""
    sim = urdf_dh.simulate(UR5, cpa=True, poses=12, noise=1e-5, seed=2,
                           errors={"elbow_joint.a": 2e-3}, name="sweeps.csv")
    path, _ = sim.write(tmp_path_factory.mktemp("cpa") / "sweeps.csv")
    return sim, path


def test_cpa_gives_the_clis_yaml(sweeps):
    sim, path = sweeps
    stdout, _, _ = _native.run(["cpa", path, "--model", str(UR5), "--format", "yaml"])
    r = urdf_dh.cpa(path, UR5)
    assert r.yaml == stdout
    assert [row["name"] for row in r.rows][:3] == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"]
    assert r.report["pairs"] and r.sheet["base_link"] == "device"


def test_a_dataframe_gives_the_file_result(sweeps):
    sim, path = sweeps
    from_file = urdf_dh.cpa(path, UR5)
    from_frame = urdf_dh.cpa(sim.frame(), UR5)
    assert from_frame.rows == from_file.rows
    assert from_frame.report["joints"] == from_file.report["joints"]


def test_without_sweeps_the_clis_error():
    sim = urdf_dh.simulate(UR5, poses=30, noise=1e-5, seed=1)
    with pytest.raises(urdf_dh.UrdfDhError, match="circle-point analysis failed") as e:
        urdf_dh.cpa(sim.frame(), UR5)
    assert e.value.hint and "sweep each joint" in e.value.hint
