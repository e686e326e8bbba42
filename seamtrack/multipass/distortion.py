"""A multi-pass job whose plates turn pass by pass (``[distortion]`` in a job's scene, issue 39
item 2): the angular distortion accumulates over the passes, and each pass tracks, and its
planner measures, a groove that has moved since the pass before.

Each welding pass locks in its own permanent angle, the single-pass relation of
:func:`seamtrack.heat.distortion.permanent_angle_rad` at the pass's heat input (``[process]``'s
thermal efficiency x U x I over the pass's travel speed) and the thickness of the section
already joined under it: the groove's depth filled once the pass is laid (at least the root
face), as the multi-layer method of W.-J. Seong, "Prediction and characteristics of angular
distortion in multi-layer butt welding", Materials 12 (2019) 1435 (doi:10.3390/ma12091435)
takes each pass on the thickness it is laid on. The angles of the passes add up (Seong, Park
and Lee, Applied Sciences 10 (2020) 1848, doi:10.3390/app10051848: the angle accumulates pass
by pass; the restraint that their model adds, which makes each increment smaller, is not in
this one). A pass starts on the angle the passes before locked in, and its own builds up behind
its arc as in a single-pass run (:class:`seamtrack.heat.motion.JointMotion`).

Everything the job keeps (the fill state, the beads, the CAD seam) stays in the part's own
frame; only the sensor sees the moved part (:class:`~seamtrack.simulation.distorted.MovingSeam`),
the pass is scored against its true path where it is, and the torch's path comes back into the
part's frame before its bead is laid.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.geometry.seam import Seam
from seamtrack.simulation.scene import Scene

if TYPE_CHECKING:
    from seamtrack.control.fill_layout import Process
    from seamtrack.control.planner import PassPlan
    from seamtrack.simulation.assemble import Parts
    from seamtrack.simulation.distorted import MovingSeam
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]


@dataclasses.dataclass
class JobDistortion:
    """The angle the passes have locked in so far (radians, both plates), and each pass's."""

    angle_rad: float = 0.0
    per_pass_rad: list[float] = dataclasses.field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """job.json's keys: the angle after the job and each pass's, in degrees."""
        return {
            "angular_distortion_deg": math.degrees(self.angle_rad),
            "angular_distortion_per_pass_deg": [math.degrees(a) for a in self.per_pass_rad],
        }


def still(scene: Scene) -> Scene:
    """``scene`` without its ``[distortion]``: the job builds each pass's parts from it and
    moves the part itself (:func:`moving_pass`)."""
    if scene.config.distortion is None:
        return scene
    return dataclasses.replace(scene, config=scene.config.model_copy(update={"distortion": None}))


def joined_thickness_mm(fill: FillState, plate_thickness_mm: float, bead_area_mm2: float) -> float:
    """The section joined under a pass once it is laid: the root face (the plate's thickness
    less the empty groove's depth, what joins the plates before any bead) plus the groove's
    depth times the fraction of its area filled (the mean over the stations, this pass's bead
    included). Area, not depth: a V fills faster in depth than in area at its root, so this
    errs towards the thinner section (the larger Q/h^2)."""
    empty = dataclasses.replace(fill, surface_z=fill.base_z)
    total = float(np.mean(np.asarray(empty.remaining_area_mm2(), dtype=float)))
    remaining = float(np.mean(np.asarray(fill.remaining_area_mm2(), dtype=float)))
    depth = float(np.mean(np.mean(fill.plate_top, axis=1) - np.min(fill.base_z, axis=1)))
    depth = min(max(depth, 0.0), plate_thickness_mm)
    root = plate_thickness_mm - depth
    filled = min(max(total - remaining + bead_area_mm2, 0.0), total) / total if total > 0 else 1.0
    return max(root + depth * filled, 0.5)


def moving_pass(
    scene: Scene, true_path: Seam, state: JobDistortion, joined_mm: float, joint: Seam
) -> MovingSeam:
    """The pass's moving part: the scene's ``[distortion]`` on the pass's true path, moved
    with the plates about the weld line ``joint`` (the CAD seam: the path's own slope over a
    bead's crown or the fill's end is no direction the plates move in), on the joined section
    ``joined_mm`` thick, starting from the angle ``state`` holds."""
    from seamtrack.simulation.distorted import moving_seam

    d = scene.config.distortion
    assert d is not None
    config = scene.config.model_copy(
        update={"distortion": d.model_copy(update={"thickness_mm": float(joined_mm)})}
    )
    moving = moving_seam(config, true_path, joint)
    motion = dataclasses.replace(moving.motion, prior_rad=state.angle_rad)
    return dataclasses.replace(moving, motion=motion)


def into_the_part(moving: MovingSeam, path: FloatArray, t_s: FloatArray) -> FloatArray:
    """The torch's path (world, on the moved part) back in the part's own frame."""
    if not len(path):
        return path
    s = moving.station_mm(path)
    return np.asarray(path - moving.shift_world(s, np.asarray(t_s, dtype=float)), dtype=float)


def distorted_parts(
    parts: Parts, scene: Scene, plan: PassPlan | None, fill: FillState, process: Process,
    state: JobDistortion | None, joint: Seam,
) -> tuple[Parts, MovingSeam | None]:  # fmt: skip
    """A welding pass's parts on the moving part (sense and scoring), and its moving seam;
    as they were, and ``None``, without ``[distortion]`` or for the scan-only pass. ``joint``:
    the weld line (the CAD seam) the plates move about."""
    d = scene.config.distortion
    if d is None or state is None or plan is None:
        return parts, None
    area = float(np.mean(process.bead_area_mm2(plan.travel_speed_mm_s, plan.wire_feed_mm_s)))
    joined = joined_thickness_mm(fill, d.thickness_mm, area)
    moving = moving_pass(scene, parts.seam, state, joined, joint)
    # the torch starts where its path is now (the part has moved since it was built)
    start = parts.tcp_start_world + moving.shift_world(np.zeros(1), np.zeros(1))[0]
    parts = dataclasses.replace(
        parts, sense=moving.sense(parts.sense), moving=moving, tcp_start_world=start
    )
    return parts, moving


def locked_in(moving: MovingSeam | None, state: JobDistortion | None) -> None:
    """After a pass: the angle it locked in added to the job's."""
    if moving is None or state is None:
        return
    state.per_pass_rad.append(float(moving.motion.permanent_rad))
    state.angle_rad += float(moving.motion.permanent_rad)
