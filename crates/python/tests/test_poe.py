"""Table.to_poe (the product-of-exponentials form) and MJCF input through the Python API."""

import math

import numpy as np
import pytest

import urdf_dh
from conftest import FIXTURES, PANDA


def expm_screw(screw, theta):
    """exp([S] theta), Modern Robotics eq. 3.88 (Rodrigues), written out here on purpose."""
    w, v = np.asarray(screw[:3], dtype=float), np.asarray(screw[3:], dtype=float)
    t = np.eye(4)
    if not w.any():
        t[:3, 3] = v * theta
        return t
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    t[:3, :3] = np.eye(3) + math.sin(theta) * k + (1 - math.cos(theta)) * k @ k
    g = np.eye(3) * theta + (1 - math.cos(theta)) * k + (theta - math.sin(theta)) * k @ k
    t[:3, 3] = g @ v
    return t


def poe_fk(poe, q):
    t = np.eye(4)
    for screw, theta in zip(poe["screws"], q):
        t = t @ expm_screw(screw, theta)
    return t @ poe["M"]


@pytest.mark.parametrize(
    "source, convention",
    [
        (PANDA, "standard"),
        (PANDA, "modified"),
        (FIXTURES / "mjcf" / "scara.xml", "standard"),
        (FIXTURES / "mjcf" / "constructs.xml", "modified"),
    ],
)
def test_poe_gives_the_tables_own_fk(source, convention):
    kwargs = {"base": "cart"} if source.name == "constructs.xml" else {}
    t = urdf_dh.extract(source, convention=convention, **kwargs)
    poe = t.to_poe()
    n = len(t.rows)
    assert poe["screws"].shape == (n, 6) and poe["M"].shape == (4, 4)
    assert poe["names"] == [r.name for r in t.rows]
    for screw, kind in zip(poe["screws"], poe["types"]):
        unit = screw[:3] if kind == "revolute" else screw[3:]
        assert np.linalg.norm(unit) == pytest.approx(1.0, abs=1e-12)
    rng = np.random.default_rng(7)
    np.testing.assert_allclose(poe_fk(poe, np.zeros(n)), t.fk(np.zeros(n)), atol=1e-12)
    for _ in range(50):
        q = rng.uniform(-2.0, 2.0, n)
        np.testing.assert_allclose(poe_fk(poe, q), t.fk(q), atol=1e-10)


def test_the_scara_screws_are_the_books():
    poe = urdf_dh.extract(FIXTURES / "mjcf" / "scara.xml").to_poe()
    # Shoulder on z through the origin, elbow on z through (0.35, 0, 0): v = -w x p = (0, -0.35, 0);
    # the quill slides down (its body is turned half a turn about x).
    np.testing.assert_allclose(poe["screws"], [[0, 0, 1, 0, 0, 0], [0, 0, 1, 0, -0.35, 0], [0, 0, 0, 0, 0, -1]], atol=1e-12)
    np.testing.assert_allclose(poe["M"][:3, 3], [0.65, 0.0, 0.35], atol=1e-12)


def test_mjcf_text_with_an_include_is_refused():
    text = (FIXTURES / "mjcf" / "constructs.xml").read_text()
    with pytest.raises(urdf_dh.UrdfDhError, match=r"<include> \(line 42\): cannot include 'forearm.xml'"):
        urdf_dh.extract(text, base="cart")
