"""The bad inputs of :mod:`seamtrack.bench.failures`: the catalogue of command lines and the
files they need (scenes, seams, plugins, STEP parts, dataset specs)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from seamtrack._version import __version__
from seamtrack.bench import (
    failure_inputs_arcprofile,
    failure_inputs_arms,
    failure_inputs_bridge,
    failure_inputs_camera,
    failure_inputs_heat,
    failure_inputs_multipass,
    failure_inputs_outputs,
    failure_inputs_parts,
    failure_inputs_ros,
    failure_inputs_units,
)
from seamtrack.bench.failure_kit import (
    ARM,
    CAMERA,
    MESH,
    SHORT,
    Entry,
    dataset_args,
    naming_key,
    run_args,
    run_set,
    seams_of,
    set_args,
    sweep_args,
)

PLUGINS = """
import math
from seamtrack.control.tracking import Command


class ExtractorBase:
    def reset(self, context):
        self.speed = context.welding_speed_mm_s

    def update(self, measurement):
        pass

    def command(self, t_s, tcp_world, tcp_velocity_world):
        return Command(tcp_world + [1.0, 0.0, 0.0], self.speed)


class RaisesInReset(ExtractorBase):
    def reset(self, context):
        raise RuntimeError("cannot start")


class RaisesInUpdate(ExtractorBase):
    def update(self, measurement):
        return 1 / 0


class RaisesInCommand(ExtractorBase):
    def command(self, t_s, tcp_world, tcp_velocity_world):
        raise KeyError("target")


class ReturnsString(ExtractorBase):
    def command(self, t_s, tcp_world, tcp_velocity_world):
        return "go"


class ReturnsShortTarget(ExtractorBase):
    def command(self, t_s, tcp_world, tcp_velocity_world):
        return Command([1.0, 2.0], self.speed)


class ReturnsNaNTarget(ExtractorBase):
    def command(self, t_s, tcp_world, tcp_velocity_world):
        return Command([math.nan, 0.0, 0.0], self.speed)


class ReturnsNegativeSpeed(ExtractorBase):
    def command(self, t_s, tcp_world, tcp_velocity_world):
        return Command(tcp_world + [1.0, 0.0, 0.0], -5.0)


class RaisingExtractor:
    name = "raising"

    def __call__(self, profile):
        raise ValueError("no idea")


class NaNExtractor:
    name = "nan-point"

    def __call__(self, profile):
        from seamtrack.sensing.profiles import Feature

        return Feature.found([math.nan, 0.0], profile.T_world_sensor, joint=self.name)
"""

FILES: dict[str, bytes] = {
    "bad_plugins.py": PLUGINS.encode(),
    "binary.toml": bytes(range(256)) * 4,
    "empty.toml": b"",
    "comments.toml": b"# nothing but a comment\n",
    "syntax.toml": b"[simulation\nwelding_speed_mm_s = 5\n",
    "nan.csv": b"x_mm,y_mm,z_mm\n0,0,0\n1,nan,0\n2,0,0\n",
    "one.csv": b"x_mm,y_mm,z_mm\n0,0,0\n",
    "text.csv": b"x_mm,y_mm,z_mm\n0,zero,0\n",
    "a_file": b"not a folder\n",
    "broken.urdf": b"<robot name='x'><link name='a'/><joint name='j' type='revolute'>",
    # --- dataset specs (seamtrack dataset)
    "dataset.toml": b'rays = 16\nchunk_size = 4\n[joint]\nfamilies = ["v-groove"]\n',
    "dataset_min_max.toml": b"[joint]\ngap_mm = [2.0, 1.0]\n",
    "dataset_family.toml": b'[joint]\nfamilies = ["v-groove", "x-groove"]\n',
    "dataset_key.toml": b"[sensor]\ntilt_degs = 5\n",
    "dataset_material.toml": b'[part]\nmaterials = ["mild-steel"]\n',
    "dataset_image_chunk.toml": b"images = true\nchunk_size = 1024\n",
    "dataset_line.toml": b"images = true\n[camera]\nline_thickness_mm = 50.0\n",
    "dataset_bits.toml": b"[camera]\nbit_depth = 17\n",
    # a dataset folder written by another spec (its manifest is what a resume reads)
    "other_dataset/dataset.json": json.dumps(
        {
            "format": "seamtrack-dataset",
            "seamtrack_version": __version__,
            "n": 8,
            "spec": {"seed": 7, "rays": 16},
        }
    ).encode(),
    "weld.toml": b'[seam]\nsource = "workpiece"\n[workpiece]\nstep = "apart.step"\n'
    b'seam = "s1"\n[sensor]\nmode = "mesh"\n',
}


def _no_solid(path: Path) -> None:
    """A STEP file that holds a face and no solid."""
    import cadquery as cq

    cq.exporters.export(cq.Face.makePlane(10, 10), str(path))


def _apart(path: Path) -> None:
    """A STEP assembly of two boxes 10 mm apart: solids that never touch."""
    import cadquery as cq

    assembly = cq.Assembly(name="apart")
    assembly.add(cq.Solid.makeBox(10, 10, 10), name="a")
    assembly.add(cq.Solid.makeBox(10, 10, 10, cq.Vector(20, 0, 0)), name="b")
    assembly.export(str(path), exportType="STEP")


#: Files made when the workspace is (CadQuery imported then, not with this module).
GENERATED: dict[str, Any] = {"sheet.step": _no_solid, "apart.step": _apart}


CATALOGUE: tuple[Entry, ...] = (
    # --- scene files and keys
    naming_key("unknown key", run_set("sensor.frame_rte_hz=2")),
    naming_key("'yes' for a boolean", run_set('sensor.quantize="yes"')),
    Entry("false for a number", run_set("sensor.look_ahead_mm=false"), field="look_ahead"),
    naming_key("true for a seed", run_set("simulation.seed=true")),
    Entry("NaN speed", run_set("simulation.welding_speed_mm_s=nan"), field="welding_speed"),
    Entry("binary scene file", ("check", "binary.toml"), field="SCENE"),
    Entry("empty scene file", ("check", "empty.toml"), field="SCENE"),
    Entry("comment-only scene file", ("check", "comments.toml"), field="SCENE"),
    Entry("TOML syntax error", ("check", "syntax.toml"), field="syntax.toml"),
    Entry("missing scene file", run_args("missing.toml"), field="SCENE"),
    Entry("unknown built-in scene", run_args("paper-verifcation"), field="SCENE"),
    # --- sizes that would not fit in memory
    naming_key("1e8 rays", run_set("sensor.rays=100000000")),
    naming_key("unknown laser fan", run_set('sensor.fan="optix"')),
    Entry(
        "plane-section fan in float32",
        run_set('sensor.fan="section"', "sensor.refine_float64=false"),
        field="sensor.fan",
    ),
    naming_key("seam step 1e-6 mm", run_set("seam.step_mm=1e-6")),
    Entry("seam length 1e9 mm", run_set("seam.length_mm=1e9"), field="seam.step_mm"),
    Entry("control period 1e-8 s", run_set("robot.control_period_s=1e-8"), field="control"),
    Entry("trace period 1e-9 s", run_set("simulation.trace_period_s=1e-9"), field="trace"),
    Entry("near-zero speed", run_set("simulation.welding_speed_mm_s=1e-3"), field="control"),
    naming_key("mesh tolerance 1e-9 mm", run_args(*MESH, *set_args("workpiece.tolerance_mm=1e-9"))),
    naming_key(
        "mesh tolerance too fine for the part",
        run_args("paper-v-groove", *set_args("workpiece.tolerance_mm=2e-4")),
        quick=False,
    ),
    # --- seam files
    naming_key("NaN in a seam file", run_set('seam.source="csv"', 'seam.file="nan.csv"')),
    Entry("one-point seam", run_set('seam.source="csv"', 'seam.file="one.csv"'), field="seam"),
    Entry("text in a seam file", run_set('seam.source="csv"', 'seam.file="text.csv"')),
    Entry("missing seam file", run_set('seam.source="csv"', 'seam.file="nope.csv"')),
    Entry("points source without points", run_set('seam.source="points"'), field="points"),
    # --- free-form sections
    *(
        Entry(f"stripe_noise {kv}", run_set(f"sensor.stripe_noise.{kv}"), field=kv.split("=")[0])
        for kv in (
            "range_sigma_mm=-1",
            "dropout_rate=2",
            "secondary_probability=1e9",
            "range_sigma_mm=inf",
            "speckle_correlation_rays=inf",
            "bogus=1",
            'dropout_rate="high"',
        )
    ),
    *(
        Entry(
            f"tracker.params {kv}",
            run_set('tracker.name="trajectory"', f"tracker.params.{kv}"),
            field=kv.split("=")[0],
        )
        for kv in ("gain_1_s=[1,2]", 'gain_1_s="x"', "bridge_mm=-inf", "use_capture_pose=1")
    ),
    naming_key("unknown tracker", run_set('tracker.name="nope"')),
    naming_key("missing tracker module", run_set('tracker.name="nomod:X"')),
    naming_key("negative radius", run_set("tracker.radius_mm=-1")),
    # --- impossible optics and geometry
    Entry("unknown preset", run_set('sensor.preset="nope"'), field="preset"),
    Entry("impossible field of view", run_set("sensor.fov_near_mm=100"), field="sensor"),
    Entry("seam out of reach", run_set("seam.offset_mm=[500, 0, 0]"), field="seam"),
    Entry("frame rate below control", run_set("sensor.frame_rate_hz=5000"), field="control"),
    # --- articulated arms
    naming_key("unknown robot model", run_set('robot.model="ur10"')),
    naming_key("URDF that does not parse", run_set('robot.urdf="broken.urdf"')),
    Entry(
        "seam point out of an arm's reach",
        run_set(*ARM[:2], "robot.base_origin_mm=[-1400,-700,0]"),
        field="seam",
    ),
    naming_key(
        "sensor mounted inside the part", run_set(*ARM, "robot.tool.sensor_xyz_mm=[10,0,-60]")
    ),
    Entry("servo gain that rings", run_set("robot.servo_gain_1_s=900"), field="servo_gain"),
    # --- the camera (image mode)
    naming_key("f-number 0", run_set("sensor.camera.f_number=0")),
    naming_key("f-number -2.8", ("render", *CAMERA, *set_args("sensor.camera.f_number=-2.8"))),
    naming_key("wavelength 150 nm", run_set("sensor.camera.wavelength_nm=150")),
    naming_key(
        "wavelength 2500 nm", ("render", *CAMERA, *set_args("sensor.camera.wavelength_nm=2500"))
    ),
    naming_key("line wider than the field", run_set("sensor.camera.line_thickness_mm=30")),
    naming_key(
        "roi off the chip", run_set("sensor.camera.rows=100", "sensor.camera.roi=[0, 200, 0, 50]")
    ),
    naming_key("unknown peak detector", run_set('sensor.camera.method="peak"')),
    naming_key("unknown material", ("render", *CAMERA, *set_args('workpiece.material="chrome"'))),
    naming_key("image mode without a mesh", run_set('sensor.source="image"')),
    Entry(
        "render a seam-mode scene",
        ("render", "paper-verification", "--at", "10"),
        field="sensor.mode",
    ),
    Entry("unknown real sensor", run_set('sensor.preset="gocator-2331"'), field="preset"),
    # --- CAD
    naming_key(
        "unknown CAD parameter",
        run_args(*MESH, *set_args("workpiece.params.bogus_mm=1")),
        quick=False,
    ),
    naming_key(
        "boolean CAD parameter",
        run_args(*MESH, *set_args("workpiece.params.groove_angle_deg=true")),
        quick=False,
    ),
    naming_key(
        "missing CAD script", run_args(*MESH, *set_args('workpiece.script="missing_part.py"'))
    ),
    naming_key(
        "unknown extractor", run_args(*MESH, *set_args('extractor.name="nope"')), quick=False
    ),
    # --- user code
    *(
        Entry(
            f"tracker {cls}",
            run_args(*SHORT, *set_args(f'tracker.name="bad_plugins:{cls}"')),
            field="tracker.name",
        )
        for cls in (
            "RaisesInReset",
            "RaisesInUpdate",
            "RaisesInCommand",
            "ReturnsString",
            "ReturnsShortTarget",
            "ReturnsNaNTarget",
            "ReturnsNegativeSpeed",
        )
    ),
    *(
        Entry(
            f"extractor {cls}",
            run_args(*MESH, *set_args(f'extractor.name="bad_plugins:{cls}"')),
            quick=False,
            field="extractor.name",
        )
        for cls in ("RaisingExtractor", "NaNExtractor")
    ),
    # --- command-line flags
    Entry(
        "sweep --workers 0",
        sweep_args("tracker.radius_mm", "1", "--workers", "0"),
        field="--workers",
    ),
    Entry(
        "sweep --seeds -1",
        sweep_args("tracker.radius_mm", "1", "--seeds", "-1"),
        field="--seeds",
    ),
    Entry(
        "sweep over a bad value",
        sweep_args("tracker.radius_mm", "1,-1"),
        field="tracker.radius_mm",
    ),
    Entry(
        "sweep over an unknown key",
        sweep_args("tracker.radius", "1"),
        field="tracker.radius",
    ),
    Entry(
        "compare with an unknown tracker",
        ("compare", "paper-corner", "--trackers", "I,nope", "--out", "OUT"),
        field="tracker.name",
    ),
    Entry("scan off the seam", ("scan", "paper-verification", "--at", "-5"), field="--at"),
    Entry("init an unknown template", ("init", "nope", "-o", "OUT/x.toml"), field="TEMPLATE"),
    Entry("output under a file", ("run", *SHORT, "--out", "a_file/run"), field="--out"),
    Entry("unknown benchmark", ("bench", "nope", "--out", "OUT"), field="bench"),
    Entry(
        "extractor.expect with an unknown key",
        run_args(*MESH, *set_args("extractor.expect={angel_deg=60}")),
        field="extractor.expect.angel_deg",
    ),
    naming_key(
        "extractor.expect on the generic extractor",
        (
            "run",
            *MESH,
            *set_args('extractor.name="generic"', "extractor.expect={angle_deg=60}"),
            "--out",
            "OUT",
        ),
    ),
    Entry(
        "groove extractor with an unknown reference",
        (
            "run",
            *MESH,
            *set_args('extractor.name="groove"', 'extractor.params={reference="middle"}'),
            "--out",
            "OUT",
        ),
        field="extractor.reference",
    ),
    # --- weldments and weldx
    seams_of("seams of a STEP without solids", "sheet.step"),
    seams_of("seams of solids that never touch", "apart.step"),
    naming_key(
        "weldment scene, STEP without solids",
        run_args("weld.toml", *set_args('workpiece.step="sheet.step"')),
    ),
    Entry("weldment scene, solids that never touch", run_args("weld.toml"), field="workpiece.step"),
    naming_key(
        "workpiece.seam naming no seam",
        run_args("weldment-bracket", *set_args('workpiece.seam="s99"')),
    ),
    naming_key(
        "groove weldx does not define",
        run_args("weldx-v-groove", *set_args('workpiece.groove.type="ZGroove"')),
    ),
    Entry(
        "groove missing parameters",
        (
            "run",
            "weldx-v-groove",
            *set_args('workpiece.groove={type="VGroove", t_mm=10}'),
            "--out",
            "OUT",
        ),
        field="workpiece.groove.alpha_deg",
    ),
    Entry("--weldx under a file", run_args(*SHORT, "--weldx", "a_file/run.wx"), field="--weldx"),
    Entry("unknown sensor preset", ("sensor", "--preset", "nope"), field="preset"),
    # --- seamtrack dataset
    Entry("dataset range min > max", dataset_args("dataset_min_max.toml"), field="joint.gap_mm"),
    Entry("dataset unknown joint family", dataset_args("dataset_family.toml"), field="families.1"),
    Entry("dataset unknown spec key", dataset_args("dataset_key.toml"), field="sensor.tilt_degs"),
    Entry("dataset --n 0", dataset_args("dataset.toml", n="0"), field="--n"),
    Entry("dataset --n -5", dataset_args("dataset.toml", n="-5"), field="--n"),
    Entry(
        "dataset --workers 0", (*dataset_args("dataset.toml"), "--workers", "0"), field="--workers"
    ),
    Entry(
        "dataset output is a file",
        ("dataset", "dataset.toml", "--n", "8", "--out", "a_file"),
        field="--out",
    ),
    Entry(
        "dataset resume with another spec",
        ("dataset", "dataset.toml", "--n", "8", "--out", "other_dataset"),
        field="--out",
    ),
    Entry(
        "dataset unknown material", dataset_args("dataset_material.toml"), field="part.materials.0"
    ),
    Entry(
        "dataset images chunk too large",
        dataset_args("dataset_image_chunk.toml"),
        field="chunk_size",
    ),
    Entry(
        "dataset images line too thick",
        dataset_args("dataset_line.toml"),
        field="camera.line_thickness_mm",
    ),
    Entry(
        "dataset camera bit depth 17",
        dataset_args("dataset_bits.toml", images=True),
        field="camera.bit_depth",
    ),
    Entry("dataset missing spec file", dataset_args("missing.toml"), field="SPEC"),
    # --- the newer features, each area in its own module
    *failure_inputs_camera.ENTRIES,
    *failure_inputs_arms.ENTRIES,
    *failure_inputs_parts.ENTRIES,
    *failure_inputs_bridge.ENTRIES,
    *failure_inputs_ros.ENTRIES,
    *failure_inputs_multipass.ENTRIES,
    *failure_inputs_heat.ENTRIES,
    *failure_inputs_outputs.ENTRIES,
    *failure_inputs_units.ENTRIES,
    *failure_inputs_arcprofile.ENTRIES,
)

_AREAS = (
    failure_inputs_camera,
    failure_inputs_arms,
    failure_inputs_parts,
    failure_inputs_bridge,
    failure_inputs_ros,
    failure_inputs_multipass,
    failure_inputs_heat,
    failure_inputs_outputs,
    failure_inputs_units,
    failure_inputs_arcprofile,
)


def workspace(root: Path) -> Path:
    """Write the catalogue's files into ``root``; return it."""
    files = dict(FILES)
    generated = dict(GENERATED)
    for area in _AREAS:
        files.update(area.FILES)
        generated.update(area.GENERATED)
    for name, data in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_bytes(data)
    for name, make in generated.items():
        make(root / name)
    return root
