"""Each row's time (seconds) from Python: ``time=`` of ``calibrate``, ``predict`` and
``compensate`` (and a DataFrame's ``time`` column), what ``thermal_growth`` reads.

The data are a warm-up simulated by the tool itself (``urdf-dh simulate --effect
thermal_growth=K,LN_TAU``, run in process: poses 30 s apart, a ``time`` column): the arrays with
their times must give the CSV file's calibration and the CLI's predictions to the last digit,
and without times a prediction is refused, naming the missing time.
"""

import csv

import numpy as np
import pandas as pd
import pytest

import urdf_dh
from urdf_dh import _native
from conftest import FIXTURES
from test_calibrate import JOINTS, _exact

UR5 = FIXTURES / "robots" / "ur5" / "vendor.yaml"
XYZ = ["x", "y", "z"]
# 200 ppm of growth with tau = 1200 s (ln 1200 = 7.09) over 100 poses 30 s apart; 20 um noise.
WARM_UP = ["--effect", "thermal_growth=2e-4,7.09", "--noise", "2e-5"]


def simulate(tmp, name, poses, seed):
    path = tmp / f"{name}.csv"
    argv = ["simulate", "--model", str(UR5), "--poses", str(poses), "--seed", str(seed)]
    _native.run(argv + WARM_UP + ["--out", str(path)])
    return path


def read(path):
    """The CSV as a DataFrame, numbers parsed with Python's float() (exact for the shortest
    round-trip digits the CLI writes): the arrays hold the very doubles the CSV reader reads."""
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    text = ("target", "config")
    return pd.DataFrame({k: [r[k] if k in text else float(r[k]) for r in rows] for k in rows[0]})


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """The warm-up set, its auto calibration from the file (written to ``cal.yaml``), and a
    program of 20 other timed poses."""
    tmp = tmp_path_factory.mktemp("warm")
    data = simulate(tmp, "warm", 100, 13)
    cal = tmp / "cal.yaml"
    from_file = urdf_dh.calibrate(UR5, data, effects="auto", out=cal)
    program = simulate(tmp, "program", 20, 14)
    return tmp, data, from_file, cal, program


def test_arrays_with_times_select_and_fit_thermal_growth_as_the_file(warm):
    _, data, from_file, _, _ = warm
    assert from_file.selected_effects == ["thermal_growth"]
    frame = read(data)
    assert list(frame["time"][:3]) == [0.0, 30.0, 60.0]
    from_array = urdf_dh.calibrate(UR5, frame[JOINTS + XYZ].to_numpy(), effects="auto", time=frame["time"].to_numpy())
    from_frame = urdf_dh.calibrate(UR5, frame, effects="auto")
    assert from_frame.parameters == from_file.parameters
    # The array has no target column: its one target is named `tip`, the file's `t1`.
    unnamed = lambda r: [{k: v for k, v in p.items() if k != "name"} for p in r.parameters]
    assert unnamed(from_array) == unnamed(from_file)
    for report in (from_array, from_frame):
        assert report.selected_effects == ["thermal_growth"]
        assert report.rms_after == from_file.rms_after
    # Without times the pose order (0 to 1) is t: another tau, so the times did cross.
    untimed = urdf_dh.calibrate(UR5, frame[JOINTS + XYZ].to_numpy(), effects=["thermal_growth"])
    assert untimed.parameter("thermal_growth.ln_tau")["estimate"] != from_file.parameter("thermal_growth.ln_tau")["estimate"]


def test_predict_and_compensate_with_times_are_the_clis(warm):
    _, _, _, cal, program = warm
    frame = read(program)
    q, t = frame[JOINTS].to_numpy(), frame["time"].to_numpy()
    out, _, _ = _native.run(["predict", "--model", str(cal), "--joints", str(program)])
    cli = _exact(out)
    p = urdf_dh.predict(cal, q, time=t)
    np.testing.assert_array_equal(p.points, cli[XYZ].to_numpy())
    np.testing.assert_array_equal(p.uncertainty, cli[["u_x", "u_y", "u_z"]].to_numpy())
    # The growth acts: the first and the last pose at t = 0 differ from them at their times.
    early = urdf_dh.predict(cal, q, time=np.zeros(len(t)))
    assert np.linalg.norm(early.points[-1] - p.points[-1]) > 1e-5
    np.testing.assert_array_equal(early.points[0], p.points[0])
    out, _, _ = _native.run(["compensate", "--nominal", str(UR5), "--model", str(cal), "--joints", str(program)])
    cli = _exact(out)
    c_q, c_errors, _ = urdf_dh.compensate(UR5, cal, q, time=t)
    np.testing.assert_array_equal(c_q, cli[JOINTS].to_numpy())
    keys = ["position_before", "orientation_before", "position_error", "orientation_error"]
    np.testing.assert_array_equal(c_errors, cli[keys].to_numpy())
    # A DataFrame's own time column is read too.
    np.testing.assert_array_equal(urdf_dh.predict(cal, frame[JOINTS + ["time"]]).points, p.points)


def test_without_times_the_refusal_names_the_missing_time(warm):
    _, _, _, cal, program = warm
    q = read(program)[JOINTS].to_numpy()
    for call in (lambda: urdf_dh.predict(cal, q), lambda: urdf_dh.compensate(UR5, cal, q)):
        with pytest.raises(urdf_dh.UrdfDhError, match=r"<joints>: the calibration's thermal_growth needs each row's time: expected a 'time' column \(seconds\), found none \(.*was fitted on times in seconds, `time_unit: s`\)") as e:
            call()
        # The calibration's data had times: the rows' order would be no time in seconds.
        assert "time=" in e.value.hint and "sequence=True" not in e.value.hint
    with pytest.raises(urdf_dh.UrdfDhError, match="was fitted on times in seconds") as e:
        urdf_dh.predict(cal, q, sequence=True)
    assert "the rows' order given with sequence=True is no time in seconds" in e.value.hint


def test_bad_times_raise_the_cli_messages(warm):
    _, data, _, cal, program = warm
    frame = read(data)
    array, t = frame[JOINTS + XYZ].to_numpy(), frame["time"].to_numpy()
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<data>: expected 100 values in 'time' \(100 rows\), found 99"):
        urdf_dh.calibrate(UR5, array, effects=["thermal_growth"], time=t[:99])
    bad = t.copy()
    bad[4] = np.inf
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<data>: row 4, column 'time': expected a finite time in seconds, found inf"):
        urdf_dh.calibrate(UR5, array, effects=["thermal_growth"], time=bad)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"time: with data given as a file, the times are its 'time' column"):
        urdf_dh.calibrate(UR5, data, time=t)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"time: data has a 'time' column already"):
        urdf_dh.calibrate(UR5, frame, time=t)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"expected a 1-D array"):
        urdf_dh.calibrate(UR5, array, time=t.reshape(-1, 1))
    q = read(program)[JOINTS].to_numpy()
    # A row without a time (NaN, as an empty cell) among timed ones; named as the file's line.
    empty = 30.0 * np.arange(len(q))
    empty[5] = np.nan
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<joints>: line 7, column 'time': expected the row's time \(seconds\) for thermal_growth, found an empty cell"):
        urdf_dh.predict(cal, q, time=empty)


def test_validation_arrays_take_their_times_as_a_validation_file(warm, tmp_path):
    _, data, _, _, _ = warm
    lines = [line for line in open(data) if not line.startswith("#")]
    first, rest = tmp_path / "first.csv", tmp_path / "rest.csv"
    first.write_text("".join(lines[:81]))
    rest.write_text(lines[0] + "".join(lines[81:]))
    from_files = urdf_dh.calibrate(UR5, first, validate=rest, effects=["thermal_growth"])
    a, b = read(first), read(rest)
    from_arrays = urdf_dh.calibrate(
        UR5,
        a[JOINTS + XYZ].to_numpy(),
        time=a["time"].to_numpy(),
        validate=b[JOINTS + XYZ].to_numpy(),
        validate_time=b["time"].to_numpy(),
        effects=["thermal_growth"],
    )
    assert from_arrays.val_rms_after == from_files.val_rms_after
    assert [p["estimate"] for p in from_arrays.parameters] == [p["estimate"] for p in from_files.parameters]
    with pytest.raises(urdf_dh.UrdfDhError, match="validate_time: expected it with validate, found no validate"):
        urdf_dh.calibrate(UR5, a[JOINTS + XYZ].to_numpy(), validate_time=b["time"].to_numpy())
