"""urdf_dh.extract on SDFormat (text or a file): the same reader and proof as the CLI."""


import numpy as np
import pytest

import urdf_dh
from conftest import REPO

# Two links 1 m apart along x, the child turned 90 degrees about z; the joint frame (the child's,
# by default) puts the axis "1 0 0" along the world's y (SDFormat 1.7).
SDF = """<sdf version="1.7"><model name="m">
  <link name="a"/>
  <link name="b"><pose>1 0 0 0 0 1.5707963267948966</pose></link>
  <joint name="j" type="revolute"><parent>a</parent><child>b</child>
    <axis><xyz>1 0 0</xyz><limit><lower>-1</lower><upper>1</upper></limit></axis></joint>
</model></sdf>"""


def test_sdf_text_extracts_with_the_axis_in_the_joint_frame():
    t = urdf_dh.extract(SDF)
    assert [r.name for r in t.rows] == ["j"]
    assert t.verification["passed"]
    # The tip turns about the world's y axis through (1, 0, 0): at q = 0.5 it stays at (1, 0, 0).
    np.testing.assert_allclose(t.fk([0.5])[:3, 3], [1.0, 0.0, 0.0], atol=1e-12)


def test_a_joint_type_without_one_axis_is_an_error_naming_it():
    with pytest.raises(Exception, match="found 'ball'"):
        urdf_dh.extract(SDF.replace('type="revolute"', 'type="ball"'))


SHARED = REPO.parent / "shared" / "formats" / "sdf" / "gazebo_models"


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared (gazebo_models SDF files) is absent")
def test_the_gazebo_ur10_extracts_as_ur_publishes_it():
    t = urdf_dh.extract(str(SHARED / "ur10" / "ur10.sdf"), base="base", tip="wrist_3")
    assert t.verification["passed"]
    a = [abs(r.a) for r in t.rows]
    assert a[1] == pytest.approx(0.612, abs=1e-6) and a[2] == pytest.approx(0.5723, abs=1e-6)
