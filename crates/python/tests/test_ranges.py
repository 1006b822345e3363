"""Every Python entry point takes the CLI's ranges (dh_workflows::ranges) with the CLI's messages,
and no failed verification or NaN passes silently (issue 30, class 9)."""

import subprocess

import numpy as np
import pytest

import urdf_dh
from conftest import FIXTURES, PANDA
from test_extract import TWO_R, cli_binary

VALID_ARM = FIXTURES / "invalid" / "urdf" / "valid_arm.urdf"
TILTED = FIXTURES / "invalid" / "urdf" / "tilted_axes.urdf"


def clap_message(args):
    """The range message of the CLI's usage error for `args` (after `'--option <X>': `)."""
    run = subprocess.run([cli_binary(), *args], capture_output=True, text=True)
    assert run.returncode == 2, run.stderr
    first = run.stderr.splitlines()[0]
    return first.split("': ", 1)[1]


@pytest.mark.parametrize(
    "kwargs, option",
    [
        ({"samples": 0}, ["--samples", "0"]),
        ({"samples": 10**12}, ["--samples", str(10**12)]),
        ({"linear_tolerance": 5}, ["--linear-tol", "5"]),
        ({"angular_tolerance": 4.0}, ["--angular-tol", "4.0"]),
        ({"linear_tolerance": float("nan")}, ["--linear-tol", "nan"]),
        ({"linear_tolerance": 5e-1}, ["--linear-tol", "0.5"]),
    ],
)
def test_extract_arguments_take_the_clis_ranges(kwargs, option):
    name, value = next(iter(kwargs.items()))
    with pytest.raises(urdf_dh.UrdfDhError) as e:
        urdf_dh.extract(VALID_ARM, **kwargs)
    # The CLI's message, the Python argument named instead of the option.
    assert str(e.value) == f"{name}: " + clap_message(["extract", str(VALID_ARM), *option])


def test_negative_and_fractional_counts_are_usage_errors_not_overflow():
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^samples: expected a number of samples, found '-1'$"):
        urdf_dh.extract(VALID_ARM, samples=-1)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^samples: expected a number of samples, found '1.5'$"):
        urdf_dh.extract(VALID_ARM, samples=1.5)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^seed: expected an integer in \[0, "):
        urdf_dh.extract(VALID_ARM, seed=-1)
    t = urdf_dh.extract(VALID_ARM, samples=np.int64(1))
    assert t.verification["samples"] == 1


def test_a_failed_verification_raises_with_the_clis_line_and_the_table():
    # The tilted axes snapped by loose tolerances: the CLI prints the table and exits 1.
    run = subprocess.run(
        [cli_binary(), "extract", str(TILTED), "--angular-tol", "0.1", "--linear-tol", "0.1"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 1, run.stderr
    line = next(l for l in run.stderr.splitlines() if l.startswith("urdf-dh: error: "))
    with pytest.raises(urdf_dh.VerificationFailed) as e:
        urdf_dh.extract(TILTED, angular_tolerance=0.1, linear_tolerance=0.1)
    assert isinstance(e.value, urdf_dh.UrdfDhError)
    assert "urdf-dh: error: " + str(e.value) == line
    assert "verification failed: forward kinematics of the table as written strays" in str(e.value)
    assert e.value.table.verification["passed"] is False
    assert len(e.value.table.rows) > 0


def test_fk_refuses_nan_naming_the_joint_and_complex_values():
    t = urdf_dh.extract(TWO_R)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^fk: joint 'j1': expected a joint value in \[-100, 100\], found NaN$"):
        t.fk([float("nan"), 0.0])
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^fk: joint 'j2': .*found inf$"):
        t.fk([0.0, float("inf")])
    with pytest.raises(urdf_dh.UrdfDhError, match="expected real numbers, found complex"):
        t.fk(np.array([0.5 + 1j, 0.0]))
    with pytest.raises(urdf_dh.UrdfDhError, match="expected real numbers, found complex"):
        t.fk([0.5 + 0j, 0.0])
    # Real values are unchanged: the hand-checked planar arm.
    m = t.fk(np.array([0.5, 0.0]))
    assert np.allclose(m[:3, 3], [0.5 * np.cos(0.5), 0.5 * np.sin(0.5), 0.0], atol=1e-12)


def test_check_and_cpa_tolerances_take_the_clis_ranges():
    sheet = FIXTURES / "invalid" / "sheet" / "valid_arm.yaml"
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^linear_tolerance: expected a length in metres in \[0, 0.1\], found 2$"):
        urdf_dh.check(VALID_ARM, sheet, linear_tolerance=2)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^angular_tolerance: expected a real number, found 1j$"):
        urdf_dh.check(VALID_ARM, sheet, angular_tolerance=1j)
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^linear_tol: expected a length in metres in \[0, 0.1\], found 2.0$"):
        urdf_dh.cpa(FIXTURES / "invalid" / "csv" / "valid_arm.csv", VALID_ARM, linear_tol=2)


def test_calibrate_sigma_below_a_nanometre_is_refused():
    data = FIXTURES / "invalid" / "csv" / "valid_arm.csv"
    with pytest.raises(urdf_dh.UrdfDhError, match=r"^sigma: expected a length in \[1e-9, 1000\], found 1e-300$"):
        urdf_dh.calibrate(VALID_ARM, data, sigma=1e-300)
    tiny = FIXTURES / "invalid" / "csv" / "tiny_sigma.csv"
    with pytest.raises(urdf_dh.UrdfDhError, match="at least 1e-9 m in column 'sigma', found '1e-300'"):
        urdf_dh.calibrate(VALID_ARM, tiny)
