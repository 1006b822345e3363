"""urdf_dh.simulate: the command line's simulator in process, and a round trip through calibrate."""

import pytest

import urdf_dh
from urdf_dh import _native
from conftest import FIXTURES

UR5 = FIXTURES / "robots" / "ur5" / "vendor.yaml"
PLANTED = {"shoulder_lift_joint.a": 0.0005, "elbow_joint.theta": 0.001}
NOISE = 5e-5


def test_simulate_writes_what_the_cli_writes(tmp_path):
    sim = urdf_dh.simulate(
        UR5, poses=40, noise=NOISE, errors=PLANTED, effects={"gear_ratio:wrist_1_joint": 2e-3},
        targets=2, seed=5, name="d.csv",
    )
    out, truth = tmp_path / "d.csv", tmp_path / "d.truth.yaml"
    argv = ["simulate", "--model", str(UR5), "--poses", "40", "--noise", repr(NOISE), "--targets", "2",
            "--seed", "5", "--effect", "gear_ratio:wrist_1_joint=0.002", "--out", str(out)]
    for k, v in PLANTED.items():
        argv += ["--error", f"{k}={v!r}"]
    _native.run(argv)
    assert sim.csv == out.read_text()
    assert sim.truth_yaml == truth.read_text()
    assert dict(sim.truth["truth"]["errors"]) == PLANTED
    assert sim.truth["truth"]["effects"] == [["gear_ratio:wrist_1_joint", 2e-3]]
    assert len(sim.frame()) == 80
    # Written as the CLI writes: never over the model, both files or neither.
    with pytest.raises(urdf_dh.UrdfDhError, match="found the input model"):
        sim.write(tmp_path / "e.csv", truth=UR5)
    assert not (tmp_path / "e.csv").exists()
    path, truth_path = sim.write(tmp_path / "e.csv")
    assert open(path).read() == sim.csv and truth_path.endswith("e.truth.yaml")


def test_the_planted_errors_come_back_from_a_simulated_dataframe():
    sim = urdf_dh.simulate(UR5, poses=150, noise=NOISE, errors=PLANTED, seed=7)
    r = urdf_dh.calibrate(UR5, sim.frame(), sigma=NOISE)
    for name, planted in PLANTED.items():
        p = r.parameter(name)
        assert abs(p["estimate"] - p["nominal"] - planted) < 4 * p["std_error"], p


def test_bad_options_are_the_clis_errors():
    with pytest.raises(urdf_dh.UrdfDhError, match="poses"):
        urdf_dh.simulate(UR5, poses=0)
    with pytest.raises(urdf_dh.UrdfDhError, match="no_such_joint"):
        urdf_dh.simulate(UR5, errors={"no_such_joint.a": 1e-3})
    with pytest.raises(TypeError):
        urdf_dh.simulate(UR5, errors="elbow_joint.a=1e-3")


def test_gravity_plants_a_sag_along_it_as_the_cli_does(tmp_path):
    # A robot on a wall (gravity along -x): the same data and truth as `simulate --gravity`.
    wall = (-9.81, 0.0, 0.0)
    sag = {"gravity_sag:shoulder_lift_joint": 6e-4}
    sim = urdf_dh.simulate(UR5, poses=30, noise=NOISE, effects=sag, gravity=wall, seed=67, name="w.csv")
    out, truth = tmp_path / "w.csv", tmp_path / "w.truth.yaml"
    _native.run(["simulate", "--model", str(UR5), "--poses", "30", "--noise", repr(NOISE), "--seed", "67",
                 "--gravity", "-9.81,0,0", "--effect", "gravity_sag:shoulder_lift_joint=6e-4", "--out", str(out)])
    assert sim.csv == out.read_text()
    assert sim.truth_yaml == truth.read_text()
    assert sim.truth["truth"]["gravity_model"]["gravity"] == list(wall)
    # Without it the sag hangs along -z: other points.
    down = urdf_dh.simulate(UR5, poses=30, noise=NOISE, effects=sag, seed=67, name="w.csv")
    assert down.truth["truth"]["gravity_model"]["gravity"] == [0.0, 0.0, -9.80665]
    assert down.csv != sim.csv


def test_bad_gravity_is_the_clis_error():
    with pytest.raises(urdf_dh.UrdfDhError, match=r"--gravity: expected three finite numbers X,Y,Z in m/s², found \[0\.0, -9\.81\]"):
        urdf_dh.simulate(UR5, gravity=(0.0, -9.81))
    with pytest.raises(urdf_dh.UrdfDhError, match=r"gravity: expected an acceleration in m/s² in \[-100, 100\], found 1000\.0"):
        urdf_dh.simulate(UR5, gravity=(1000.0, 0.0, 0.0))
