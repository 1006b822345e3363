"""urdf_dh.extract / check: the CLI's results, numpy out, the CLI's messages as exceptions."""

import math
import pathlib
import subprocess

import numpy as np
import pytest

import urdf_dh
from conftest import FIXTURES, PANDA, REPO

TWO_R = """
<robot name="planar">
  <link name="base"/><link name="l1"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="tip"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/></joint>
</robot>
"""


def planar_tip(q1, q2, l1=0.5):
    return np.array([l1 * math.cos(q1), l1 * math.sin(q1), 0.0])


def test_panda_rows_and_verification():
    t = urdf_dh.extract(PANDA)
    assert [r.name for r in t.rows] == [f"panda_joint{i}" for i in range(1, 8)]
    assert all(r.type == "revolute" for r in t.rows)
    assert t.rows[0].d == pytest.approx(0.333, abs=1e-12)
    assert t.rows[0].lower == pytest.approx(-2.8973)
    assert t.convention == "standard"
    assert t.base.shape == (4, 4) and t.tool.shape == (4, 4)
    v = t.verification
    assert v["passed"] is True and v["samples"] == 1000
    assert v["max_position_error"] <= v["position_bound"]


def test_hand_checked_planar_2r_from_xml_text():
    t = urdf_dh.extract("  \n" + TWO_R)
    assert [r.name for r in t.rows] == ["j1", "j2"]
    assert t.rows[1].lower is None and t.rows[1].upper is None
    assert (t.rows[0].lower, t.rows[0].upper) == (-1.0, 2.0)
    for q1, q2 in [(0.0, 0.0), (0.3, -1.2), (-1.0, 2.5)]:
        pose = t.fk(np.array([q1, q2]))
        assert isinstance(pose, np.ndarray) and pose.shape == (4, 4)
        np.testing.assert_allclose(pose[:3, 3], planar_tip(q1, q2), atol=1e-12)
        # tip frame rotated by q1 + q2 about z
        np.testing.assert_allclose(pose[0, 0], math.cos(q1 + q2), atol=1e-12)
        np.testing.assert_allclose(pose[1, 0], math.sin(q1 + q2), atol=1e-12)


def test_modified_convention_same_fk():
    s = urdf_dh.extract(PANDA)
    m = urdf_dh.extract(str(PANDA), convention="modified")
    assert m.convention == "modified"
    q = np.random.default_rng(7).uniform(-2, 2, 7)
    np.testing.assert_allclose(s.fk(q), m.fk(q), atol=1e-12)


def test_pathlike_and_str_agree():
    assert urdf_dh.extract(pathlib.Path(PANDA)).to_yaml() == urdf_dh.extract(str(PANDA)).to_yaml()


def cli_binary():
    """The urdf-dh binary of this checkout (target/debug, else target/release), or skip."""
    # debug first: `cargo test --workspace` (CI) builds it fresh
    for exe in [REPO / "target" / "debug" / "urdf-dh",
                REPO / "target" / "release" / "urdf-dh"]:
        if exe.exists():
            return str(exe)
    pytest.skip("the urdf-dh binary is not built (cargo build): cannot compare with the CLI")


def test_yaml_is_the_clis():
    out = subprocess.run(
        [cli_binary(), "extract", str(PANDA), "--format", "yaml"],
        capture_output=True, text=True, check=True,
    ).stdout
    assert urdf_dh.extract(PANDA).to_yaml() == out


def test_to_dict_is_the_sheet():
    d = urdf_dh.extract(PANDA).to_dict()
    assert d["robot"] == "panda"
    assert len(d["joints"]) == 7
    assert d["verification"]["passed"] is True


def test_fk_wrong_length_is_an_error():
    t = urdf_dh.extract(PANDA)
    with pytest.raises(urdf_dh.UrdfDhError, match="7"):
        t.fk([0.0, 0.0])


def test_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no_such.urdf: cannot read the file"):
        urdf_dh.extract("no_such.urdf")


def test_invalid_urdf_message_is_the_clis():
    with pytest.raises(ValueError) as e:
        urdf_dh.extract("<robot name='x'><link name='a'/><link name='a'/></robot>")
    assert isinstance(e.value, urdf_dh.UrdfDhError)
    assert str(e.value).startswith("<string>: invalid URDF:")


def test_invalid_corpus_gives_the_clis_messages():
    """Every bad URDF of the corpus: the CLI's exit 2 is a UrdfDhError with its message and hint."""
    cli = cli_binary()
    bad = sorted((FIXTURES / "invalid" / "urdf").glob("*.urdf"))
    assert len(bad) > 10
    errors = 0
    for path in bad:
        run = subprocess.run([cli, "extract", str(path)], capture_output=True, text=True)
        if run.returncode == 1:
            # The CLI prints the table and exits 1: Python raises its error line.
            message = next(l for l in run.stderr.splitlines() if l.startswith("urdf-dh: error: "))
            with pytest.raises(urdf_dh.VerificationFailed) as e:
                urdf_dh.extract(path)
            assert "urdf-dh: error: " + str(e.value) == message, path.name
            continue
        if run.returncode != 2:
            urdf_dh.extract(path)  # readable (maybe with warnings): must not raise
            continue
        errors += 1
        lines = run.stderr.splitlines()
        message = next(l for l in lines if l.startswith("urdf-dh: error: "))
        hint = next((l[len("hint: "):] for l in lines if l.startswith("hint: ")), None)
        with pytest.raises(urdf_dh.UrdfDhError) as e:
            urdf_dh.extract(path)
        assert "urdf-dh: error: " + str(e.value) == message, path.name
        assert e.value.hint == hint, path.name
    assert errors > 10


def test_unknown_tip_has_hint():
    with pytest.raises(urdf_dh.UrdfDhError) as e:
        urdf_dh.extract(PANDA, tip="no_such_link")
    assert "no_such_link" in str(e.value)
    assert e.value.hint and "--tip" in e.value.hint


def test_bad_convention():
    with pytest.raises(urdf_dh.UrdfDhError, match="expected 'standard' or 'modified'"):
        urdf_dh.extract(PANDA, convention="craig")


def test_check_panda_against_its_sheet():
    sheet = FIXTURES / "robots" / "franka_panda" / "vendor.yaml"
    if not sheet.exists():
        pytest.skip(f"{sheet} absent")
    r = urdf_dh.check(PANDA, sheet)
    assert r.matches and r.verdict == "match" and r.differences == []
    assert r.to_dict()["matches"] is True


def test_check_finds_a_difference(tmp_path):
    sheet = FIXTURES / "robots" / "franka_panda" / "vendor.yaml"
    if not sheet.exists():
        pytest.skip(f"{sheet} absent")
    import re

    text = sheet.read_text()
    # lengthen joint 3's d (not the first: a free base absorbs it): check must name it
    changed = re.sub(r"(panda_joint3,.*d: )0\.316\b", r"\g<1>0.326", text, count=1)
    assert changed != text, "the vendor sheet has panda_joint3 d: 0.316"
    p = tmp_path / "dh.yaml"
    p.write_text(changed)
    r = urdf_dh.check(PANDA, p)
    assert not r.matches and r.verdict == "mismatch"
    assert any(d["parameter"] == "d" and d["joint"] == "panda_joint3" for d in r.differences), r.differences


def test_xacro_expanded_natively_with_args_and_packages():
    arm = FIXTURES / "xacro" / "demo_arm_description" / "urdf" / "arm.urdf.xacro"
    pkgs = {"demo_arm_description": FIXTURES / "xacro" / "demo_arm_description"}
    long = urdf_dh.extract(arm, xacro_args={"reach": "long"}, packages=pkgs)
    short = urdf_dh.extract(arm, packages=pkgs)
    assert [r.name for r in long.rows] == ["joint1", "joint2", "joint3"]
    assert long.rows[1].a == pytest.approx(0.6, abs=1e-12)
    assert short.rows[1].a == pytest.approx(0.45, abs=1e-12)
    with pytest.raises(urdf_dh.UrdfDhError, match="package 'demo_arm_description' not found"):
        urdf_dh.extract(arm)
