"""predict and compensate of a calibrated tree from Python: a torso of two joints carrying two
arms of three (the tree of the CLI's tests/cli/tree.rs), simulated here with planted errors,
calibrated with ``out=``, predicted branch by branch at unseen poses against the truth, and
compensated for one branch (only the trunk's and that branch's joints move). Figures of this
seeded run (calibration seed 31, 60 poses, 20 um noise per axis): 30 unseen poses predicted to
8.3 um (branch r) and 7.9 um (branch l) RMS per coordinate, RMS of error/u 1.12 and 1.14; the
true right tool 2.25 mm RMS off the nominal one at 10 commanded poses, 25.5 um compensated."""

import numpy as np
import pytest

import urdf_dh

JOINTS = ["t1", "t2", "r1", "r2", "r3", "l1", "l2", "l3"]

# Errors planted in the truth (metres, radians).
PLANTED = {
    "t2.a": 2e-3,
    "t2.alpha": 3e-3,
    "r2.a": -1.5e-3,
    "r2.alpha": 2e-3,
    "r2.theta": -2.5e-3,
    "r3.a": 1e-3,
    "l2.a": 1.2e-3,
    "l2.alpha": -2e-3,
}
NOISE = 2e-5
PI2 = np.pi / 2


def _rows(e):
    """(trunk, right, left) rows as (name, a, alpha, d, theta), metres and radians."""
    v = lambda name, nominal: nominal + e.get(name, 0.0)  # noqa: E731
    trunk = [("t1", 0.0, 0.0, 0.1, 0.0), ("t2", v("t2.a", 0.05), v("t2.alpha", PI2), 0.0, 0.0)]
    right = [
        ("r1", 0.0, 0.0, 0.0, 0.0),
        ("r2", v("r2.a", 0.05), v("r2.alpha", -PI2), 0.0, v("r2.theta", 0.0)),
        ("r3", v("r3.a", 0.3), 0.0, 0.02, 0.0),
    ]
    left = [
        ("l1", 0.0, 0.0, 0.0, 0.0),
        ("l2", v("l2.a", 0.05), v("l2.alpha", PI2), 0.0, 0.0),
        ("l3", 0.3, 0.0, 0.0, 0.0),
    ]
    return trunk, right, left


# Mounts (xyz, rpy) in the branch point frame, and the trunk's base and tool.
BASE = ([0, 0, 0.4], [0, 0, 0])
TOOL = ([0, 0, 0.15], [0, 0, 0])
MOUNTS = {"r": ([0.1, -0.2, 0], [PI2, 0, 0]), "l": ([0.1, 0.2, 0], [-PI2, 0, 0])}
TIP = ([0, 0, 0.08], [0, 0, 0])


def _sheet(e):
    trunk, right, left = _rows(e)
    pose = lambda p: f"{{xyz: {list(p[0])}, rpy: {list(p[1])}}}"  # noqa: E731
    joints = lambda rows, pad: "".join(  # noqa: E731
        f"{pad}- {{name: {n}, type: revolute, a: {a!r}, alpha: {al!r}, d: {d!r}, theta: {th!r}}}\n"
        for n, a, al, d, th in rows
    )
    text = (
        "convention: modified\nlength_unit: m\nangle_unit: rad\n"
        f"base: {pose(BASE)}\ntool: {pose(TOOL)}\njoints:\n{joints(trunk, '  ')}branches:\n"
    )
    for name, rows in (("r", right), ("l", left)):
        text += f"  - name: {name}\n    base: {pose(MOUNTS[name])}\n    tool: {pose(TIP)}\n"
        text += f"    joints:\n{joints(rows, '      ')}"
    return text


def _pose(xyz, rpy):
    r, p, y = rpy
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    t = np.eye(4)
    t[:3, :3] = rz @ ry @ rx
    t[:3, 3] = xyz
    return t


def _link(a, alpha, d, theta):
    """Modified DH: Rx(alpha) Tx(a) Rz(theta) Tz(d)."""
    return _pose([a, 0, 0], [alpha, 0, 0]) @ _pose([0, 0, d], [0, 0, theta])


def _tips(e, q):
    """Both branches' tips (4x4, base link frame) at joint values q (8)."""
    trunk, right, left = _rows(e)
    t = _pose(*BASE)
    for (_, a, al, d, th), v in zip(trunk, q[:2]):
        t = t @ _link(a, al, d, th + v)
    t = t @ _pose(*TOOL)
    tips = []
    for name, rows, qs in (("r", right, q[2:5]), ("l", left, q[5:])):
        b = t @ _pose(*MOUNTS[name])
        for (_, a, al, d, th), v in zip(rows, qs):
            b = b @ _link(a, al, d, th + v)
        tips.append(b @ _pose(*TIP))
    return tips


DEVICE = _pose([1.2, -0.3, 0.2], [0.02, -0.01, 0.4])
OFFSETS = [np.array([0.01, 0.02, 0.03, 1.0]), np.array([-0.02, 0.01, 0.04, 1.0])]
TARGETS = ["r", "l/hand"]


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    d = tmp_path_factory.mktemp("tree")
    nominal = d / "tree.yaml"
    nominal.write_text(_sheet({}))
    rng = np.random.default_rng(31)
    lines = [",".join(JOINTS) + ",x,y,z,target,config,sigma"]
    for p in range(60):
        q = rng.uniform(-1.5, 1.5, 8)
        for b, tip in enumerate(_tips(PLANTED, q)):
            x = (DEVICE @ tip @ OFFSETS[b])[:3] + rng.normal(0.0, NOISE, 3)
            cells = [repr(float(v)) for v in q] + [repr(float(v)) for v in x]
            lines.append(",".join(cells + [TARGETS[b], f"p{p}", repr(NOISE)]))
    data = d / "d.csv"
    data.write_text("\n".join(lines) + "\n")
    out = d / "cal.yaml"
    urdf_dh.calibrate(nominal, data, effects="none", out=out)
    return nominal, out


def test_each_branch_is_predicted_against_the_truth(calibrated):
    _, cal = calibrated
    q = np.random.default_rng(32).uniform(-1.5, 1.5, (30, 8))
    for b, branch in enumerate(["r", "l"]):
        p = urdf_dh.predict(cal, q, branch=branch)
        assert p.frame == "device" and p.targets == [TARGETS[b]] * len(q)
        truth = np.array([(DEVICE @ _tips(PLANTED, row)[b] @ OFFSETS[b])[:3] for row in q])
        err = p.points - truth
        rms = np.sqrt(np.mean(err**2))
        assert rms < 1e-5, (branch, rms)
        z = err / p.uncertainty[:, :3]
        assert 0.5 < np.sqrt(np.mean(z**2)) < 2.0, (branch, z)
    # The tool of a tree of two branches needs one; an unknown one is named.
    with pytest.raises(urdf_dh.UrdfDhError, match=r"expected --branch NAME to say whose tool"):
        urdf_dh.predict(cal, q, targets="tool")
    with pytest.raises(urdf_dh.UrdfDhError, match=r"expected one of 'r', 'l'"):
        urdf_dh.predict(cal, q, branch="left")


def test_a_branch_is_compensated(calibrated):
    nominal, cal = calibrated
    q = np.random.default_rng(33).uniform(-1.2, 1.2, (10, 8))
    c, errors, failures = urdf_dh.compensate(nominal, cal, q, branch="r", position_only=True)
    assert failures == [] and c.shape == q.shape
    assert np.array_equal(c[:, 5:], q[:, 5:])  # the left arm as commanded
    wanted = np.array([_tips({}, row)[0][:3, 3] for row in q])
    before = np.array([_tips(PLANTED, row)[0][:3, 3] for row in q]) - wanted
    after = np.array([_tips(PLANTED, row)[0][:3, 3] for row in c]) - wanted
    rms = lambda v: np.sqrt(np.mean(np.sum(v**2, axis=1)))  # noqa: E731
    assert rms(before) > 1e-3 and rms(after) < 5e-5, (rms(before), rms(after))
