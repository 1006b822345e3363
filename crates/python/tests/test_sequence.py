"""``predict(..., sequence=True)`` and ``compensate(..., sequence=True)``: the joint values in the
order the robot moves through them, as the CLI's ``--sequence`` (each joint's approach direction
for a ``backlash_direction`` effect, each pose's place in the order for ``drift``).

The data are simulated by the tool itself (``urdf-dh simulate``, run in process) with the effect
planted, so the truth is known; each call is held to the CLI's CSV to its last digit and to the
true robot.
"""

import warnings

import numpy as np
import pandas as pd
import pytest

import urdf_dh
from urdf_dh import _native
from conftest import FIXTURES
from test_calibrate import JOINTS, _exact

UR5 = FIXTURES / "robots" / "ur5" / "vendor.yaml"
NOISE = 5e-5


def simulate(tmp, name, poses, seed, extra):
    """``urdf-dh simulate`` of the UR5 (50 um noise, one target); returns (data, truth) paths."""
    data, truth = tmp / f"{name}.csv", tmp / f"{name}.truth.yaml"
    argv = ["simulate", "--model", str(UR5), "--poses", str(poses), "--seed", str(seed)]
    argv += ["--noise", repr(NOISE)] + extra + ["--out", str(data), "--truth", str(truth)]
    _native.run(argv)
    return data, truth


def cli(argv):
    out, _, _ = _native.run(argv)
    return _exact(out)


@pytest.fixture(scope="module")
def backlash(tmp_path_factory):
    """A UR5 with 0.3 mrad of play each side on the elbow, calibrated with the effect, and a
    program of 40 other poses in the order the robot runs them."""
    tmp = tmp_path_factory.mktemp("backlash")
    effect = ["--effect", "backlash_direction:elbow_joint=3e-4"]
    data, truth = simulate(tmp, "data", 150, 41, effect + ["--error", "shoulder_lift_joint.a=0.0005"])
    cal = tmp / "cal.yaml"
    urdf_dh.calibrate(UR5, data, effects=["backlash_direction:elbow_joint"], out=cal)
    program, _ = simulate(tmp, "program", 40, 42, [])
    return tmp, cal, truth, program


def tool(model, joints, **kw):
    return urdf_dh.predict(model, joints, targets="tool", frame="base", **kw)


def test_predict_in_sequence_is_the_clis_and_puts_each_pose_on_its_flank(backlash):
    tmp, cal, truth, program = backlash
    q = pd.read_csv(program, comment="#")[JOINTS].to_numpy()
    args = ["predict", "--model", str(cal), "--joints", str(program), "--targets", "tool", "--frame", "base"]
    seq_cli = cli(args + ["--sequence"])
    # A file and an array give the CLI's numbers; only the first pose (nothing moved yet) has
    # its flank unknown, and the warning says so.
    with pytest.warns(UserWarning, match=r"at 1 of 40 row\(s\)"):
        seq = tool(cal, program, sequence=True)
    np.testing.assert_array_equal(seq.points, seq_cli[["x", "y", "z"]].to_numpy())
    u = ["u_x", "u_y", "u_z", "u_rx", "u_ry", "u_rz"]
    np.testing.assert_array_equal(seq.uncertainty, seq_cli[u].to_numpy())
    with pytest.warns(UserWarning, match=r"at 1 of 40 row\(s\)"):
        np.testing.assert_array_equal(tool(cal, q, sequence=True).points, seq.points)
    # Without the order: the CLI's midway prediction, the half backlash in the uncertainty.
    with pytest.warns(UserWarning, match=r"at 40 of 40 row\(s\).*with sequence=True"):
        mid = tool(cal, q)
    np.testing.assert_array_equal(mid.points, cli(args)[["x", "y", "z"]].to_numpy())
    assert np.all(np.linalg.norm(mid.uncertainty[1:, :3], axis=1) > np.linalg.norm(seq.uncertainty[1:, :3], axis=1))
    # Against the true robot on its flanks: within the noise in sequence, off by the play
    # midway.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        true = tool(truth, q, sequence=True).points
    e_seq = np.linalg.norm(seq.points[1:] - true[1:], axis=1)
    e_mid = np.linalg.norm(mid.points[1:] - true[1:], axis=1)
    rms = lambda e: float(np.sqrt(np.mean(e**2)))  # noqa: E731
    assert rms(e_seq) < NOISE and rms(e_mid) > 2.0 * rms(e_seq), (rms(e_seq), rms(e_mid))


def test_compensate_in_sequence_is_the_clis(backlash):
    tmp, cal, _, program = backlash
    args = ["compensate", "--nominal", str(UR5), "--model", str(cal), "--joints", str(program)]
    keys = ["position_before", "orientation_before", "position_error", "orientation_error"]
    for extra, flag, unknown in (([], False, "40 of 40"), (["--sequence"], True, "1 of 40")):
        expected = cli(args + extra)
        with pytest.warns(UserWarning, match=f"at {unknown} row"):
            q, errors, _ = urdf_dh.compensate(UR5, cal, program, sequence=flag)
        np.testing.assert_array_equal(q, expected[JOINTS].to_numpy())
        np.testing.assert_array_equal(errors, expected[keys].to_numpy())
    # The two differ: in sequence each pose is corrected for its own flank.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mid, _, _ = urdf_dh.compensate(UR5, cal, program)
        seq, _, _ = urdf_dh.compensate(UR5, cal, program, sequence=True)
    assert np.max(np.abs(mid[1:, 2] - seq[1:, 2])) > 1e-4


def test_drift_is_predicted_along_the_sequence(tmp_path):
    # A device scale growing by 100 ppm over the session (100 um at 1 m), calibrated with it:
    # the measured file predicted in its own order follows the drift, without the order the
    # prediction is the session's start.
    data, _ = simulate(tmp_path, "drift", 150, 61, ["--effect", "drift=1e-4"])
    cal = tmp_path / "cal.yaml"
    r = urdf_dh.calibrate(UR5, data, effects=["drift"], out=cal)
    assert r.parameter("drift")["identified"], r.parameter("drift")
    measured = pd.read_csv(data, comment="#")
    seq = urdf_dh.predict(cal, data, sequence=True)
    with pytest.warns(UserWarning, match=r"'drift' \(c = 1\.0.*session's start.*with sequence=True"):
        start = urdf_dh.predict(cal, data)
    expected = cli(["predict", "--model", str(cal), "--joints", str(data), "--sequence"])
    np.testing.assert_array_equal(seq.points, expected[["x", "y", "z"]].to_numpy())
    xyz = measured[["x", "y", "z"]].to_numpy()
    rms = lambda d: float(np.sqrt(np.mean(np.sum(d**2, axis=1))))  # noqa: E731
    # Per coordinate the residual is the noise in sequence; from the start it grows with the
    # drift (the last poses off by about 100 ppm of their distance from the device).
    assert rms(seq.points - xyz) < 1.2 * NOISE * np.sqrt(3), rms(seq.points - xyz)
    assert rms(start.points - xyz) > 1.5 * rms(seq.points - xyz)
