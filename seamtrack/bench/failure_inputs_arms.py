"""Bad inputs for articulated arms (render and scan, arm parameters, URDF files): entries of the
catalogue in :mod:`seamtrack.bench.failure_inputs`, with the files they need."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from seamtrack.bench.failure_kit import ARM, SHORT, Entry, naming_key, run_args, set_args

#: The KUKA KR 16 where it reaches the paper's seam (the arm entries' other model).
KR16 = ('robot.model="kr16"', 'tracker.name="trajectory"', "robot.base_origin_mm=[-700,0,-300]")


def chain_urdf(
    joints: int,
    kind: str = "revolute",
    axis: str | None = None,
    limit: str | None = '<limit lower="-3.14" upper="3.14" velocity="2" effort="100"/>',
    origin: str = '<origin xyz="0 0 0.1" rpy="0 0 0"/>',
    extra: str = "",
) -> str:
    """A serial chain of ``joints`` joints (axes turning z, y, x in turn, 0.1 m apart): a valid
    URDF with the defaults, or one broken in the way the arguments say."""
    links = "".join(f'<link name="l{i}"/>' for i in range(joints + 1))
    body = "".join(
        f'<joint name="j{i + 1}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'{origin}<axis xyz="{axis or ("0 0 1", "0 1 0", "1 0 0")[i % 3]}"/>{limit or ""}'
        "</joint>\n"
        for i in range(joints)
    )
    return f'<?xml version="1.0"?>\n<robot name="chain{joints}">\n{links}\n{body}{extra}</robot>\n'


def _writer(text: Callable[[], str]) -> Callable[[Path], None]:
    def write(path: Path) -> None:
        path.write_text(text(), encoding="utf-8")

    return write


def _big(path: Path) -> None:
    """A 5 MiB URDF (white space in a valid one): past the 4 MiB a URDF may have."""
    text = chain_urdf(6)
    path.write_text(text.replace("</robot>", " " * (5 * 2**20) + "</robot>"), encoding="utf-8")


_LIMIT = '<limit lower="-3.14" upper="3.14" velocity="2" effort="100"/>'
_ENTITIES = (
    '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa">'
    + "".join(
        f'<!ENTITY {c} "{("&" + p + ";") * 10}">'
        for p, c in zip("abcdefgh", "bcdefghi", strict=True)
    )
    + ']>\n<robot name="lol"><link name="&i;"/></robot>\n'
)

#: Files written into the workspace (name -> bytes).
FILES: dict[str, bytes] = {
    "urdf_axis_nan.urdf": chain_urdf(6, axis="nan 0 1").encode(),
    "urdf_axis_zero.urdf": chain_urdf(6, axis="0 0 0").encode(),
    "urdf_origin_short.urdf": chain_urdf(6, origin='<origin xyz="0 0.1" rpy="0 0 0"/>').encode(),
    "urdf_no_velocity.urdf": chain_urdf(
        6, limit='<limit lower="-3" upper="3" effort="1"/>'
    ).encode(),
    "urdf_no_effort.urdf": chain_urdf(
        6, limit='<limit lower="-3" upper="3" velocity="1"/>'
    ).encode(),
    "urdf_no_limit.urdf": chain_urdf(6, limit="").encode(),
    "urdf_second_root.urdf": chain_urdf(6, extra='<link name="stray"/>\n').encode(),
    "urdf_two_parents.urdf": chain_urdf(
        6,
        extra=f'<joint name="again" type="revolute"><parent link="l0"/><child link="l3"/>'
        f'<axis xyz="0 0 1"/>{_LIMIT}</joint>\n',
    ).encode(),
    "urdf_unknown_parent.urdf": chain_urdf(6)
    .replace('<parent link="l2"/>', '<parent link="x"/>')
    .encode(),
    "urdf_continuous.urdf": chain_urdf(6, kind="continuous", limit=None).encode(),
    "urdf_floating.urdf": chain_urdf(6).replace('type="revolute"', 'type="floating"', 1).encode(),
    "urdf_five_joints.urdf": chain_urdf(5).encode(),
    "urdf_entities.urdf": _ENTITIES.encode(),
    "urdf_not_robot.urdf": b'<?xml version="1.0"?>\n<sdf><robot_like/></sdf>\n',
    "urdf_folder/readme.txt": b"a folder, not a URDF\n",
}

#: Files made when the workspace is (name -> a function of the path).
GENERATED: dict[str, Callable[[Path], None]] = {
    "urdf_chain_33.urdf": _writer(lambda: chain_urdf(33)),
    "urdf_chain_300.urdf": _writer(lambda: chain_urdf(300)),
    "urdf_chain_600.urdf": _writer(lambda: chain_urdf(600)),
    "urdf_fixed_500.urdf": _writer(lambda: chain_urdf(6, extra=_fixed_tail(500))),
    "urdf_big.urdf": _big,
}


def _fixed_tail(count: int) -> str:
    """``count`` fixed joints hung from the chain's last link (frames, not axes)."""
    return "".join(
        f'<link name="f{i}"/><joint name="fixed{i}" type="fixed"><parent link="l6"/>'
        f'<child link="f{i}"/></joint>\n'
        for i in range(count)
    )


def _urdf(name: str) -> tuple[str, ...]:
    return run_args(*SHORT, *set_args('tracker.name="trajectory"', f'robot.urdf="{name}"'))


def _arm(*pairs: str, model: tuple[str, ...] = ARM) -> tuple[str, ...]:
    return run_args(*SHORT, *set_args(*model, *pairs))


_ACCEL = "robot.joint_acceleration_max_deg_s2"

ENTRIES: tuple[Entry, ...] = (
    # --- render and scan on the arm scenes (they work: their bad neighbours are refused)
    Entry("render an arm scene off its seam", ("render", "pipe-saddle", "--at", "1000"),
          quick=False, field="--at"),
    Entry("scan an arm scene before its seam", ("scan", "pipe-on-plate", "--at", "-1"),
          quick=False, field="--at"),
    Entry("scan an arm scene at NaN", ("scan", "v-groove-corner-arm", "--at", "nan"),
          field="--at"),
    Entry("render an arm scene under a file",
          ("render", "v-groove-corner-arm", "--at", "10", "--out", "a_file/r.png"),
          field="--out"),
    Entry("scan an arm scene under a file",
          ("scan", "v-groove-corner-arm", "--at", "10", "--out", "a_file/s.csv"), field="--out"),
    # --- per-joint vectors against the arm's joint count
    naming_key("joint accelerations [1,2] on a UR10e", _arm(f"{_ACCEL}=[1,2]")),
    naming_key("joint accelerations [] on a UR10e", _arm(f"{_ACCEL}=[]")),
    naming_key("7 joint accelerations on a KR 16",
               _arm(f"{_ACCEL}=[90,90,90,90,90,90,90]", model=KR16)),
    naming_key("joint acceleration 1e300", _arm(f"{_ACCEL}=1e300")),
    naming_key("joint acceleration -5 in a list", _arm(f"{_ACCEL}=[90,90,-5,90,90,90]")),
    naming_key("servo gains [] on a UR10e", _arm("robot.servo_gain_1_s=[]")),
    Entry("servo gains [50,true] on a UR10e", _arm("robot.servo_gain_1_s=[50,true]"),
          field="robot.servo_gain_1_s.1"),
    naming_key("servo gains [] on the gantry",
               run_args(*SHORT, *set_args("robot.servo_gain_1_s=[]"))),
    naming_key("4 servo gains on a KR 16", _arm("robot.servo_gain_1_s=[50,50,50,50]", model=KR16)),
    # --- sizes of the robot's and the tool's fields
    naming_key("sensor 1e300 mm from the torch", _arm("robot.tool.sensor_xyz_mm=[1e300,0,0]")),
    naming_key("sensor 5 m from the torch on a KR 16",
               _arm("robot.tool.sensor_xyz_mm=[0,0,-5000]", model=KR16)),
    naming_key("sensor turned 1e300 deg", _arm("robot.tool.sensor_rpy_deg=[1e300,0,0]")),
    naming_key("torch 1 km long", _arm("robot.tool.tcp_xyz_mm=[0,0,1e6]")),
    naming_key("torch turned 720 deg", _arm("robot.tool.tcp_rpy_deg=[0,720,0]")),
    naming_key("arm base 1e300 mm away", _arm("robot.base_origin_mm=[1e300,0,0]")),
    naming_key("gantry base 1e9 mm away",
               run_args(*SHORT, *set_args("robot.base_origin_mm=[1e9,0,0]"))),
    naming_key("base turned 1e9 deg", _arm("robot.base_rotation_deg=[0,0,1e9]")),
    naming_key("start 1e300 mm off the seam", _arm("robot.start_offset_mm=[0,0,1e300]")),
    naming_key("tool speed 1e300 mm/s", _arm("robot.tcp_velocity_max_mm_s=[1e300,1,1]")),
    naming_key("tool acceleration 1e9 mm/s^2 on a KR 16",
               _arm("robot.tcp_acceleration_max_mm_s2=[1e9,500,500]", model=KR16)),
    naming_key("tool turning 1e300 deg/s", _arm("robot.angular_velocity_max_deg_s=1e300")),
    naming_key("tool turning acceleration 1e300 deg/s^2",
               _arm("robot.angular_acceleration_max_deg_s2=1e300")),
    # --- URDF files
    naming_key("URDF /dev/zero", _urdf("/dev/zero")),
    naming_key("URDF a folder", _urdf("urdf_folder")),
    naming_key("URDF of 5 MiB", _urdf("urdf_big.urdf")),
    naming_key("URDF chain of 300 joints", _urdf("urdf_chain_300.urdf")),
    naming_key("URDF chain of 600 joints", _urdf("urdf_chain_600.urdf")),
    naming_key("URDF chain of 33 joints", _urdf("urdf_chain_33.urdf")),
    naming_key("URDF with 500 fixed joints", _urdf("urdf_fixed_500.urdf")),
    naming_key("URDF axis nan 0 1", _urdf("urdf_axis_nan.urdf")),
    naming_key("URDF axis 0 0 0", _urdf("urdf_axis_zero.urdf")),
    naming_key("URDF origin of 2 numbers", _urdf("urdf_origin_short.urdf")),
    naming_key("URDF limit without velocity", _urdf("urdf_no_velocity.urdf")),
    naming_key("URDF limit without effort", _urdf("urdf_no_effort.urdf")),
    naming_key("URDF revolute joint without limit", _urdf("urdf_no_limit.urdf")),
    naming_key("URDF second root link", _urdf("urdf_second_root.urdf")),
    naming_key("URDF link with two parents", _urdf("urdf_two_parents.urdf")),
    naming_key("URDF joint from an unknown link", _urdf("urdf_unknown_parent.urdf")),
    naming_key("URDF six continuous joints", _urdf("urdf_continuous.urdf")),
    naming_key("URDF floating joint", _urdf("urdf_floating.urdf")),
    naming_key("URDF of 5 joints", _urdf("urdf_five_joints.urdf")),
    naming_key("URDF with entities", _urdf("urdf_entities.urdf")),
    naming_key("URDF whose root is not robot", _urdf("urdf_not_robot.urdf")),
)  # fmt: skip
