"""A user's URDF is read bounded and checked before Pinocchio (urdfdom) sees it; the bounds leave
every real arm in: a chain of the most joints allowed still loads, and its kinematics are right."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from seamtrack.bench.failure_inputs_arms import chain_urdf
from seamtrack.control.kinematics import ArmKinematics
from seamtrack.control.urdf import MAX_JOINTS, MAX_URDF_BYTES
from seamtrack.errors import SceneError


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "arm.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_chain_of_the_most_joints_allowed_loads_and_its_kinematics_are_right(
    tmp_path: Path,
) -> None:
    kin = ArmKinematics.from_urdf(_write(tmp_path, chain_urdf(MAX_JOINTS)))
    assert kin.dof == MAX_JOINTS
    # Oracle: at zero the chain is straight up, 0.1 m (100 mm) per joint, to the last link.
    T = kin.fk(np.zeros(MAX_JOINTS))
    np.testing.assert_allclose(T[:3, 3], [0.0, 0.0, 100.0 * MAX_JOINTS], atol=1e-9)
    # The first joint (about z, 100 mm up) turned 90 deg takes the second's y axis to -x; the
    # second (200 mm up) turned 90 deg about it lays the rest of the chain along +y: the last
    # joint (n - 2) x 100 mm from the second.
    q = np.zeros(MAX_JOINTS)
    q[0] = q[1] = math.pi / 2
    expected = [0.0, 100.0 * (MAX_JOINTS - 2), 200.0]
    np.testing.assert_allclose(kin.fk(q)[:3, 3], expected, atol=1e-9)


def test_one_joint_more_than_allowed_is_refused_with_the_count(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match=rf"robot.urdf: .*has {MAX_JOINTS + 1} movable joints"):
        ArmKinematics.from_urdf(_write(tmp_path, chain_urdf(MAX_JOINTS + 1)))


def test_a_file_at_the_size_bound_is_read_and_one_byte_more_is_not(tmp_path: Path) -> None:
    text = chain_urdf(6)
    pad = MAX_URDF_BYTES - len(text.encode())
    ArmKinematics.from_urdf(_write(tmp_path, text.replace("</robot>", " " * pad + "</robot>")))
    with pytest.raises(SceneError, match="larger than 4 MiB"):
        big = text.replace("</robot>", " " * (pad + 1) + "</robot>")
        ArmKinematics.from_urdf(_write(tmp_path, big))


def test_a_device_is_refused_without_reading_it() -> None:
    with pytest.raises(SceneError, match="not a regular file"):
        ArmKinematics.from_urdf("/dev/zero")


def test_six_continuous_joints_are_named_as_such(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match="joint 'j1' is continuous") as info:
        ArmKinematics.from_urdf(_write(tmp_path, chain_urdf(6, kind="continuous", limit=None)))
    # named as continuous, not counted among the too-many movable joints (the message holds
    # the file's path, whose pytest-NNN folder may hold any digits)
    assert "movable joints" not in str(info.value)


@pytest.mark.parametrize(
    ("text", "said"),
    [
        (chain_urdf(6, axis="nan 0 1"), '<axis xyz="nan 0 1"> must be 3 finite numbers'),
        (chain_urdf(6, limit='<limit lower="-3" upper="3" effort="1"/>'), "no velocity"),
        (chain_urdf(6, extra='<link name="stray"/>'), "2 root links"),
    ],
)
def test_what_urdfdom_would_print_is_our_one_error_and_nothing_on_the_c_stderr(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], text: str, said: str
) -> None:
    with pytest.raises(SceneError, match="robot.urdf") as info:
        ArmKinematics.from_urdf(_write(tmp_path, text))
    assert said in str(info.value)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_the_built_in_arms_still_load() -> None:
    for name in ("ur10e", "kr16"):
        assert ArmKinematics.named(name).dof == 6
