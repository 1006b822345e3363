"""urdf_dh.calibrate / predict / compensate on a simulated UR5 with planted errors.

The data are simulated by the tool itself (``urdf-dh simulate``, run in process), so the truth is
known: the fit must find the planted errors, ``predict`` must match the true robot within its own
uncertainty, and ``compensate`` must bring the true robot's tool to the nominal goal.
"""

import csv
import math

import numpy as np
import pandas as pd
import pytest

import urdf_dh
from urdf_dh import _native
from conftest import FIXTURES

UR5 = FIXTURES / "robots" / "ur5" / "vendor.yaml"
JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]
# Planted: 0.5 mm on the shoulder's a, 1 mrad on the elbow's theta; 50 um noise per axis.
PLANTED = {"shoulder_lift_joint.a": 0.0005, "elbow_joint.theta": 0.001}
NOISE = 5e-5


def simulate(tmp, name, poses, seed, noise=NOISE, planted=True, validation=0.0):
    """Runs ``urdf-dh simulate`` (one target); returns (data path, truth path)."""
    data, truth = tmp / f"{name}.csv", tmp / f"{name}.truth.yaml"
    argv = ["simulate", "--model", str(UR5), "--poses", str(poses), "--seed", str(seed)]
    argv += ["--noise", repr(noise), "--validation", repr(validation)]
    if planted:
        for k, v in PLANTED.items():
            argv += ["--error", f"{k}={v}"]
    argv += ["--out", str(data), "--truth", str(truth)]
    _native.run(argv)
    return data, truth


def read(path):
    return pd.read_csv(path, comment="#")


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ur5")
    data, truth = simulate(tmp, "data", 150, 7)
    return tmp, data, truth


def test_calibrate_finds_the_planted_errors(tmp_path):
    # The last 40 of 200 poses held out (the `set` column), then handed over as two DataFrames
    # without that column: the same device frame, another set of poses.
    both = read(simulate(tmp_path, "both", 200, 7, validation=0.2)[0])
    fit, held = (both[both.set == s].drop(columns="set") for s in ("calibration", "validation"))
    assert len(held) == 40
    r = urdf_dh.calibrate(UR5, fit, validate=held, sigma=NOISE)
    assert isinstance(r, urdf_dh.Report)
    assert r.rms_before > 5e-4 and r.rms_after < 1.5 * NOISE * math.sqrt(3)
    assert r.val_rms_after is not None and r.val_rms_after < 1.5 * NOISE * math.sqrt(3)
    for name, planted in PLANTED.items():
        p = r.parameter(name)
        assert p["free"]
        assert abs(p["estimate"] - p["nominal"] - planted) < 4 * p["std_error"], p
    with pytest.raises(KeyError):
        r.parameter("no_such_joint.a")
    assert r.device.shape == (4, 4)
    np.testing.assert_allclose(r.device[:3, :3] @ r.device[:3, :3].T, np.eye(3), atol=1e-12)
    assert r.steps and r.to_dict()["rms_after"] == r.rms_after
    assert "complete" in str(r.verdict)


def test_dataframe_and_array_give_the_file_result(sets):
    _, data, _ = sets
    from_file = urdf_dh.calibrate(UR5, data)
    frame = read(data)
    from_frame = urdf_dh.calibrate(UR5, frame)
    array = frame[JOINTS + ["x", "y", "z"]].to_numpy()
    from_array = urdf_dh.calibrate(UR5, array)
    # The CSV text of a DataFrame or array is written at 17 significant digits: the same fit.
    assert from_frame.rms_after == pytest.approx(from_file.rms_after, rel=1e-9)
    assert from_array.rms_after == pytest.approx(from_file.rms_after, rel=1e-9)
    with pytest.raises(ValueError, match="expected 9 columns"):
        urdf_dh.calibrate(UR5, array[:, :8])
    bad = array.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        urdf_dh.calibrate(UR5, bad)


def test_predict_matches_the_true_robot_within_its_uncertainty(sets):
    tmp, data, truth = sets
    cal = tmp / "cal.yaml"
    r = urdf_dh.calibrate(UR5, data, out=cal)
    assert r.written is not None and cal.exists()
    q = np.random.default_rng(3).uniform(-3.0, 3.0, size=(40, 6))
    # In the device frame (where the data were measured; the default of both files): the truth
    # file predicts as the simulated robot, with its device frame and targets, and has no
    # covariance.
    p = urdf_dh.predict(cal, q)
    assert p.points.shape == (40, 3) and p.uncertainty.shape == (40, 3)
    assert np.all(p.uncertainty > 0) and np.all(p.uncertainty < 1e-3)
    assert p.targets == ["t1"] * 40
    t = urdf_dh.predict(truth, q)
    assert t.uncertainty is None
    z = (p.points - t.points) / p.uncertainty
    rms_z = float(np.sqrt(np.mean(z**2)))
    assert 0.3 < rms_z < 3.0, rms_z
    # One pose as a 1-D array, in mm and degrees.
    one = urdf_dh.predict(cal, np.degrees(q[0]), length_unit="mm", angle_unit="deg")
    np.testing.assert_allclose(one.points[0], 1000 * p.points[0], atol=1e-9)
    tool = urdf_dh.predict(cal, q[:5], targets="tool", frame="base")
    assert tool.rpy.shape == (5, 3) and tool.uncertainty.shape == (5, 6)


def test_compensate_brings_the_true_robot_to_the_nominal_goal(sets):
    tmp, data, truth = sets
    cal = tmp / "cal2.yaml"
    urdf_dh.calibrate(UR5, data, out=cal)
    program = read(simulate(tmp, "program", 30, 99, noise=0.0, planted=False)[0])[JOINTS]
    q, errors, failures = urdf_dh.compensate(UR5, cal, program.to_numpy())
    assert q.shape == (30, 6) and errors.shape == (30, 4)
    # Poses without a config column are named by their line (the header is line 1). The
    # program's first pose is the zero pose (stretched arm, aligned wrist): singular, named.
    assert any(f.startswith("line2 (line 2): needs more than --max-change") for f in failures), failures
    done = [i for i in range(30) if not any(f.startswith(f"line{i + 2} ") for f in failures)]
    assert len(done) >= 25
    # Where the true robot's tool goes at the commanded and the corrected values.
    goal = urdf_dh.predict(UR5, program.to_numpy(), targets="tool", frame="base").points
    before = urdf_dh.predict(truth, program.to_numpy(), targets="tool", frame="base").points
    after = urdf_dh.predict(truth, q, targets="tool", frame="base").points
    e_before = np.linalg.norm(before - goal, axis=1)[done]
    e_after = np.linalg.norm(after - goal, axis=1)[done]
    assert np.sqrt(np.mean(e_before**2)) > 4e-4
    # What remains is the calibration's own error (tens of micrometres at 50 um noise).
    assert np.sqrt(np.mean(e_after**2)) < 0.15 * np.sqrt(np.mean(e_before**2))
    np.testing.assert_allclose(errors[done, 2], 0.0, atol=1e-6)


def test_bad_inputs_raise_the_cli_messages(sets, tmp_path):
    _, data, _ = sets
    with pytest.raises(urdf_dh.UrdfDhError, match="effect"):
        urdf_dh.calibrate(UR5, data, effects=["no_such_effect:elbow_joint"])
    missing = tmp_path / "missing.csv"
    with pytest.raises((urdf_dh.UrdfDhError, FileNotFoundError), match="missing.csv"):
        urdf_dh.calibrate(UR5, missing)
    with pytest.raises(urdf_dh.UrdfDhError, match="frame"):
        urdf_dh.predict(UR5, np.zeros((1, 6)), frame="sideways")


def test_predict_takes_each_rows_session_frame(tmp_path):
    # Two sessions (the tracker moved between them): calibrated together, each session's rows
    # are predicted from their own device frame; session="s2" predicts all from the second.
    data = tmp_path / "days.csv"
    _native.run(
        ["simulate", "--model", str(UR5), "--poses", "80", "--seed", "5", "--sessions", "2"]
        + ["--noise", repr(NOISE), "--out", str(data)]
    )
    out = tmp_path / "days-calibrated.yaml"
    urdf_dh.calibrate(UR5, data, out=out)
    measured = read(data)
    points = measured[["x", "y", "z"]].to_numpy()
    own = urdf_dh.predict(out, measured)
    assert own.sessions == list(measured.session)
    err = np.linalg.norm(own.points - points, axis=1)
    assert math.sqrt(np.mean(err**2)) < 1.5 * math.sqrt(3) * NOISE
    second = urdf_dh.predict(out, measured, session="s2")
    err = np.linalg.norm(second.points - points, axis=1)
    s1 = (measured.session == "s1").to_numpy()
    assert math.sqrt(np.mean(err[~s1] ** 2)) < 1.5 * math.sqrt(3) * NOISE
    assert np.min(err[s1]) > 100 * NOISE
    with pytest.raises(urdf_dh.UrdfDhError, match="expected one of 's2'"):
        urdf_dh.predict(out, measured, session="s9")


def test_alpha_sets_the_level_of_the_selection_and_is_checked(sets):
    _, data, _ = sets
    r = urdf_dh.calibrate(UR5, data, effects="auto", sigma=NOISE, alpha=0.05)
    doc = r.to_dict()
    assert doc["diagnosis"]["alpha"] == 0.05
    assert doc["verdict"]["alpha"] == 0.05
    assert urdf_dh.calibrate(UR5, data, effects="auto", sigma=NOISE).to_dict()["diagnosis"]["alpha"] == 0.01
    for bad in (0.0, 0.7, float("nan")):
        with pytest.raises(urdf_dh.UrdfDhError, match="alpha"):
            urdf_dh.calibrate(UR5, data, effects="auto", alpha=bad)


class _exact:
    """A CSV's columns parsed with Python's own float() (exact for the shortest round-trip
    digits the CLI writes, whatever pandas' parser does)."""

    def __init__(self, text):
        rows = list(csv.DictReader(l for l in text.splitlines() if not l.startswith("#")))
        self._rows = rows

    def __getitem__(self, key):
        if isinstance(key, list):
            return _Columns([[float(r[k]) for k in key] for r in self._rows])
        return [r[key] for r in self._rows]


class _Columns:
    def __init__(self, rows):
        self._rows = rows

    def to_numpy(self):
        return np.array(self._rows, dtype=float)


def test_predict_and_compensate_give_what_the_cli_writes(sets, tmp_path):
    """The library calls behind ``predict`` and ``compensate`` and the CLI's CSV agree to the
    digits the CSV writes (the shortest round-trip form): one computation, two renderings."""
    tmp, data, _ = sets
    cal = tmp / "cal3.yaml"
    urdf_dh.calibrate(UR5, data, out=cal)
    joints = tmp_path / "q.csv"
    q = np.random.default_rng(5).uniform(-2.0, 2.0, size=(12, 6))
    pd.DataFrame(q, columns=JOINTS).to_csv(joints, index=False)
    for extra, targets in (([], None), (["--targets", "tool", "--frame", "base"], "tool")):
        out, _, _ = _native.run(["predict", "--model", str(cal), "--joints", str(joints)] + extra)
        cli = _exact(out)
        p = urdf_dh.predict(cal, joints, targets=targets, frame="base" if targets else None)
        np.testing.assert_array_equal(p.points, cli[["x", "y", "z"]].to_numpy())
        assert p.targets == list(cli["target"]) and p.configs == list(cli["config"])
        u = ["u_x", "u_y", "u_z"] + (["u_rx", "u_ry", "u_rz"] if targets else [])
        np.testing.assert_array_equal(p.uncertainty, cli[u].to_numpy())
        if targets:
            np.testing.assert_array_equal(p.rpy, cli[["roll", "pitch", "yaw"]].to_numpy())
    out, err, _ = _native.run(["compensate", "--nominal", str(UR5), "--model", str(cal), "--joints", str(joints)])
    cli = _exact(out)
    c_q, c_errors, failures = urdf_dh.compensate(UR5, cal, joints)
    np.testing.assert_array_equal(c_q, cli[JOINTS].to_numpy())
    keys = ["position_before", "orientation_before", "position_error", "orientation_error"]
    np.testing.assert_array_equal(c_errors, cli[keys].to_numpy())
    assert failures == [line.strip() for line in err.splitlines() if line.startswith("  ")]
