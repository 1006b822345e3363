"""Arrays and DataFrames handed to calibrate / predict / compensate without files.

The library reads them as arrays (``dh_calib::csv::SampleArrays``): no temporary file, no run of
the command line, the same result as the CSV file, and errors naming the row and the column.
"""

import os
import tempfile

import numpy as np
import pandas as pd
import pytest

import urdf_dh
from urdf_dh import _native
from test_calibrate import JOINTS, NOISE, UR5, read, simulate


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("arrays")
    path, truth = simulate(tmp, "data", 60, 11)
    return tmp, path, truth


@pytest.fixture
def no_files(monkeypatch, tmp_path):
    """Fails any use of tempfile or of the command-line runner, in an empty working directory."""

    def refuse(*args, **kwargs):
        raise AssertionError("a temporary file or a command-line run was used")

    for name in ("mkstemp", "mkdtemp", "NamedTemporaryFile", "TemporaryDirectory", "TemporaryFile"):
        monkeypatch.setattr(tempfile, name, refuse)
    monkeypatch.setattr(_native, "run", refuse)
    monkeypatch.chdir(tmp_path)
    before = set(os.listdir(tempfile.gettempdir()))
    yield tmp_path
    assert list(tmp_path.iterdir()) == []
    assert set(os.listdir(tempfile.gettempdir())) - before == set()


def test_arrays_need_no_files(data, no_files):
    _, path, _ = data
    frame = read(path)
    array = frame[JOINTS + ["x", "y", "z"]].to_numpy()
    r = urdf_dh.calibrate(UR5, array, sigma=NOISE)
    assert r.rms_after < 2 * NOISE * np.sqrt(3)
    p = urdf_dh.predict(UR5, array[:, :6], targets="tool", frame="base")
    assert p.points.shape == (60, 3)
    q, errors, _ = urdf_dh.compensate(UR5, UR5, array[:5, :6])
    np.testing.assert_allclose(q, array[:5, :6], atol=1e-12)
    assert errors.shape == (5, 4)


def test_dataframe_and_array_give_identical_reports(data):
    _, path, _ = data
    frame = read(path)
    array = frame[JOINTS + ["x", "y", "z"]].to_numpy()
    # Columns in another order and a column that is no joint: used by name.
    shuffled = frame[["z"] + JOINTS[::-1] + ["x", "y"]].assign(operator="me")
    from_frame = urdf_dh.calibrate(UR5, shuffled).to_dict()
    from_array = urdf_dh.calibrate(UR5, array).to_dict()
    assert from_frame == from_array
    assert from_array["data"] == "<data>"
    # The whole file as a DataFrame (its target column too): the file's fit, the same numbers
    # (the report names the file instead of <data>).
    from_file = urdf_dh.calibrate(UR5, path).to_dict()
    whole = urdf_dh.calibrate(UR5, frame).to_dict()
    assert whole["parameters"] == from_file["parameters"]
    assert whole["steps"] == from_file["steps"]
    assert {k: v for k, v in whole.items() if k != "data"} == {
        k: v for k, v in from_file.items() if k != "data"
    }


def test_predict_and_compensate_arrays_match_the_file(data, tmp_path):
    _, path, truth = data
    q = read(path)[JOINTS].to_numpy()[:12]
    joints_csv = tmp_path / "q.csv"
    pd.DataFrame(q, columns=JOINTS).to_csv(joints_csv, index=False, float_format="%.17g")
    from_file = urdf_dh.predict(truth, joints_csv)
    from_array = urdf_dh.predict(truth, q)
    assert from_array.configs == from_file.configs
    np.testing.assert_array_equal(from_array.points, from_file.points)
    c_file = urdf_dh.compensate(UR5, truth, joints_csv)
    c_array = urdf_dh.compensate(UR5, truth, q)
    np.testing.assert_array_equal(c_array[0], c_file[0])
    np.testing.assert_array_equal(c_array[1], c_file[1])
    assert c_array[2] == c_file[2]


def test_bad_arrays_name_the_row_and_column(data):
    _, path, _ = data
    frame = read(path)
    array = frame[JOINTS + ["x", "y", "z"]].to_numpy()
    bad = array.copy()
    bad[3, 2] = np.nan
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<data>: row 3, column 'elbow_joint': expected a finite number, found NaN"):
        urdf_dh.calibrate(UR5, bad)
    bad = array.copy()
    bad[7, 7] = np.inf
    with pytest.raises(urdf_dh.UrdfDhError, match=r"row 7, column 'y': expected a finite number, found inf"):
        urdf_dh.calibrate(UR5, bad)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"expected a 2-D array .* found shape \(9,\)"):
        urdf_dh.calibrate(UR5, array[0])
    with pytest.raises(urdf_dh.UrdfDhError, match="expected 9 columns"):
        urdf_dh.calibrate(UR5, array[:, 1:])
    # Degrees handed over as radians: the reader's unit check, naming the cell.
    degrees = array.copy()
    degrees[:, :6] = np.degrees(degrees[:, :6]) + 30.0
    with pytest.raises(urdf_dh.UrdfDhError, match=r"row \d+, column '\w+_joint': expected a joint value within 25.1 rad"):
        urdf_dh.calibrate(UR5, degrees)
    with_nan = frame.copy()
    with_nan.loc[5, "x"] = np.nan
    with pytest.raises(urdf_dh.UrdfDhError, match=r"row 5, column 'x'"):
        urdf_dh.calibrate(UR5, with_nan)
    with pytest.raises(urdf_dh.UrdfDhError, match="'wrist_3_joint'"):
        urdf_dh.calibrate(UR5, frame.drop(columns="wrist_3_joint"))
    odd_set = frame.assign(set="later")
    with pytest.raises(urdf_dh.UrdfDhError, match=r"row 0, column 'set': expected train"):
        urdf_dh.calibrate(UR5, odd_set)
    joints = frame[JOINTS].to_numpy()
    joints[2, 0] = np.nan
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<joints>: row 2, column 'shoulder_pan_joint'"):
        urdf_dh.predict(UR5, joints)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<joints>: row 2, column 'shoulder_pan_joint'"):
        urdf_dh.compensate(UR5, UR5, joints)


def test_six_dof_dataframe_gives_the_file_report(tmp_path):
    """A 6-DoF set (qw, qx, qy, qz, sigma_rot columns) as a DataFrame: the same report as its
    CSV file, the target's rotation estimated; a missing orientation column is named."""
    path, truth = tmp_path / "p6.csv", tmp_path / "p6.truth.yaml"
    _native.run(
        ["simulate", "--model", str(UR5), "--poses", "60", "--seed", "4", "--noise", "2e-5",
         "--orientation-noise", "5e-5", "--out", str(path), "--truth", str(truth)]
    )
    frame = read(path)
    assert {"qw", "qx", "qy", "qz", "sigma_rot"} <= set(frame.columns)
    from_file = urdf_dh.calibrate(UR5, path).to_dict()
    from_frame = urdf_dh.calibrate(UR5, frame).to_dict()
    for doc in (from_file, from_frame):
        doc.pop("data", None)
        doc.get("names", {}).pop("data", None)
    assert from_frame["rms_after"] == from_file["rms_after"]
    assert from_frame["targets"] == from_file["targets"]
    assert "rpy" in from_frame["targets"][0]
    with pytest.raises(urdf_dh.UrdfDhError, match="missing sigma_rot"):
        urdf_dh.calibrate(UR5, frame.drop(columns=["sigma_rot"]))


def test_per_axis_sigmas_in_a_dataframe_give_the_file_report(data, tmp_path):
    """sx, sy, sz columns (a tracker's per-axis standard deviations) as a DataFrame: the same
    report as the CSV file with those columns; the three go together, and not with sigma."""
    _, path, _ = data
    frame = read(path).drop(columns=["sigma"], errors="ignore")
    rng = np.random.default_rng(3)
    for c, scale in zip(("sx", "sy", "sz"), (1.0, 2.0, 0.5)):
        frame[c] = NOISE * scale * (1.0 + 0.1 * rng.random(len(frame)))
    csv = tmp_path / "axes.csv"
    frame.to_csv(csv, index=False, float_format="%.17g")
    from_file = urdf_dh.calibrate(UR5, csv).to_dict()
    from_frame = urdf_dh.calibrate(UR5, frame).to_dict()
    assert from_frame["rms_after"] == from_file["rms_after"]
    assert from_frame["noise_floor"] == from_file["noise_floor"]
    assert from_frame["parameters"] == from_file["parameters"]
    with pytest.raises(urdf_dh.UrdfDhError, match="missing sz"):
        urdf_dh.calibrate(UR5, frame.drop(columns=["sz"]))
    both = frame.copy()
    both["sigma"] = NOISE
    with pytest.raises(urdf_dh.UrdfDhError, match="either the isotropic 'sigma'"):
        urdf_dh.calibrate(UR5, both)
