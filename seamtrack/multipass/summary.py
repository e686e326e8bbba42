"""A multi-pass job's summary (``job.json``): the passes, the layers, the final fill and its
checks (reinforcement along the seam, underfill, the sidewall fusion margin), heat input and
arc time. See :mod:`seamtrack.multipass.job`."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.planner import PassPlan, fill_order
from seamtrack.simulation.scene import Scene
from seamtrack.workpiece.inspection import MIN_THICKNESS_MM, Inspection, inspect_weld

if TYPE_CHECKING:
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]

#: A job whose fill surface lies deeper than this (mm) under the plates' top line at a station
#: every pass welded ends ``underfilled``, not ``completed``: ISO 5817:2014's limit for an
#: incompletely filled groove (imperfection 511) at quality level C, h <= 0.1 t but at most
#: 1 mm (t: the plate, here >= 10 mm).
UNDERFILL_LIMIT_MM = 1.0


def job_summary(
    scene: Scene, records: list[Any], fill: FillState, wall_s: float, stopped: str = ""
) -> dict:
    """job.json: the passes, the layers, the final fill and its checks; ``stopped``: why the
    job stopped before its planner said it was done."""
    c = scene.config
    assert c.passes is not None
    welded = [r for r in records if r.plan is not None]
    lo, hi = welded_range(welded, fill)
    keep = (fill.s_mm >= lo) & (fill.s_mm <= hi)
    reinf = np.asarray(fill.reinforcement_mm())[keep]
    remaining = np.asarray(fill.remaining_area_mm2())[keep]
    margin = fusion_margin_mm(fill, welded)[keep]
    threshold = c.passes.fusion_margin_min_mm
    flagged = fill.s_mm[keep][margin < threshold - 1e-9]
    layers: dict[int, int] = {}
    for r in welded:
        assert r.plan is not None
        layers[r.plan.layer] = layers.get(r.plan.layer, 0) + 1
    crown = reinf[:, 1]
    statuses = [r.result.status for r in records]
    errors = [float(r.result.summary.get("max_error_mm", math.nan)) for r in welded]
    status, reason = job_status(stopped, statuses, reinf[:, 0], fill.s_mm[keep])
    return {
        "scene": scene.name,
        "status": status,
        "stop_reason": reason,
        "passes": len(welded),
        "scan_pass": len(records) > len(welded),
        "layers": len(layers),
        "beads_per_layer": [layers[k] for k in sorted(layers)],
        "stations": int(keep.sum()),
        "stations_from_mm": lo,
        "stations_to_mm": hi,
        "reinforcement_min_mm": float(np.min(reinf[:, 0])),
        "reinforcement_max_mm": float(np.max(reinf[:, 1])),
        "reinforcement_spread_mm": float(np.ptp(crown)),
        "underfilled_stations": int(np.count_nonzero(reinf[:, 0] < 0.0)),
        "remaining_underfill_max_mm2": float(np.max(remaining)),
        "fusion_margin_min_mm": float(np.min(margin)) if len(margin) else math.nan,
        "fusion_margin_threshold_mm": threshold,
        "fusion_flagged_stations": len(flagged),
        "fusion_flagged_s_mm": [round(float(s), 2) for s in flagged[:50]],
        **_inspection(scene, fill, welded),
        "max_tracking_error_mm": float(np.nanmax(errors)) if errors else math.nan,
        "arc_time_s": float(sum(r.arc_time_s for r in welded)),
        "job_time_s": float(sum(float(r.result.trace.t_s[-1]) for r in records)),
        "wall_time_s": wall_s,
        "per_pass": [_pass_row(r) for r in records],
    }


def plate_thickness_mm(scene: Scene, fill: FillState) -> float:
    """The plates' thickness t for ISO 5817: the workpiece's ``plate_thickness_mm`` parameter,
    else the groove's depth below the plates' top line (a groove cut into thicker plate judged
    by its depth: the stricter limits)."""
    t = scene.config.workpiece.params.get("plate_thickness_mm") if scene.config.workpiece else None
    if t is not None:
        return float(t)
    corners_z = np.asarray(fill.top_corners)[:, :, 1].min(axis=1)
    return float(np.max(corners_z - np.asarray(fill.base_z).min(axis=1)))


def inspect_job(scene: Scene, fill: FillState, welded: list[Any]) -> Inspection | None:
    """The welded stations judged by ISO 5817 (:mod:`seamtrack.workpiece.inspection`): b the
    groove's top width, t :func:`plate_thickness_mm`, a wall bead's toe short of the wall by
    more than ``passes.fusion_margin_min_mm`` a lack of fusion. None for plate of 3 mm or
    less (ISO 5817's thin-sheet rows are not implemented) or fewer than two stations."""
    assert scene.config.passes is not None
    lo, hi = welded_range(welded, fill)
    keep = (fill.s_mm >= lo) & (fill.s_mm <= hi)
    t = plate_thickness_mm(scene, fill)
    if t <= MIN_THICKNESS_MM or np.count_nonzero(keep) < 2:
        return None
    reinf = np.asarray(fill.reinforcement_mm())[keep]
    margin = fusion_margin_mm(fill, welded)[keep]
    corners = np.asarray(fill.top_corners)[keep]
    return inspect_weld(
        np.asarray(fill.s_mm)[keep],
        thickness_mm=t,
        width_mm=np.abs(corners[:, 1, 0] - corners[:, 0, 0]),
        excess_mm=reinf[:, 1],
        underfill_mm=-reinf[:, 0],
        unfused=margin < scene.config.passes.fusion_margin_min_mm - 1e-9,
    )


def _inspection(scene: Scene, fill: FillState, welded: list[Any]) -> dict[str, Any]:
    """job.json's ``quality_level`` and ``inspection`` (see :func:`inspect_job`)."""
    weld = inspect_job(scene, fill, welded)
    if weld is None:
        return {"quality_level": None, "inspection": None}
    out = weld.as_dict()
    return {"quality_level": out["level"], "inspection": out}


def job_status(
    stopped: str, statuses: list[str], fill_top_mm: FloatArray, s_mm: FloatArray
) -> tuple[str, str]:
    """The job's status and why: ``stopped`` (the job stopped early, for ``stopped``),
    ``incomplete`` (a pass did not complete), ``underfilled`` (the fill surface lies more than
    :data:`UNDERFILL_LIMIT_MM` under the plates' top line at a station, ``fill_top_mm``: each
    station's lowest fill height over that line; the plan could not fill the groove), else
    ``completed``."""
    if stopped:
        return "stopped", stopped
    if not all(s == "completed" for s in statuses):
        return "incomplete", ""
    deep = np.flatnonzero(np.asarray(fill_top_mm) < -UNDERFILL_LIMIT_MM)
    if len(deep) or not len(fill_top_mm):
        if not len(fill_top_mm):
            return "underfilled", "no station was welded by every pass"
        worst = int(np.argmin(fill_top_mm))
        return "underfilled", (
            f"{len(deep)} of {len(fill_top_mm)} stations lie more than {UNDERFILL_LIMIT_MM:g} mm "
            f"under the plates' top line ({-float(fill_top_mm[worst]):.3g} mm at s = "
            f"{float(s_mm[worst]):.4g} mm): the plan did not fill the groove"
        )
    return "completed", ""


def _pass_row(r: Any) -> dict[str, Any]:
    s = r.result.summary
    row: dict[str, Any] = {
        "name": r.name,
        "status": s.get("status"),
        "max_error_mm": s.get("max_error_mm"),
        "rms_error_mm": s.get("rms_error_mm"),
        "arc_time_s": r.arc_time_s,
        "mean_speed_mm_s": r.mean_speed_mm_s,
        "build_s": r.build_s,
        "run_s": r.run_s,
        "deposit_s": r.deposit_s,
    }
    if r.plan is not None:
        p = r.plan
        row.update(layer=p.layer + 1, bead_in_layer=p.bead_in_layer + 1, cap=p.cap,
                   reference=p.reference, offset_mm=p.offset_mm,
                   wire_feed_m_min=p.wire_feed_mm_s * 60e-3, bead_area_mm2=r.bead_area_mm2,
                   heat_input_kj_mm=r.heat_input_kj_mm, plan_s=r.plan_s,
                   plan_cpu_s=r.plan_cpu_s)  # fmt: skip
    return row


def welded_range(welded: list[Any], fill: FillState) -> tuple[float, float]:
    """The arc lengths every pass laid its bead over (the stations all passes covered)."""
    covered = np.ones(len(fill.s_mm), dtype=bool)
    for bead in fill.beads:
        covered &= np.isfinite(bead.y_centre_mm)
    if not covered.any():
        return float(fill.s_mm[0]), float(fill.s_mm[0])
    s = fill.s_mm[covered]
    return float(s[0]), float(s[-1])


def fusion_margin_mm(fill: FillState, welded: list[Any]) -> FloatArray:
    """(m,) per station, how far the wall beads' toes reach past the wall (the smallest over
    the beads laid against a wall, > 0 fused, < 0 a gap; +inf where no bead meets a wall).

    A wall bead: a fill layer's bead in a wall slot (the first and last slot, corners first;
    a layer's only bead), or one tracking a wall's foot."""
    margins = np.asarray(fill.sidewall_margin_mm())
    out = np.full(len(fill.s_mm), np.inf)
    for k, r in enumerate(welded):
        if k < margins.shape[1] and r.plan is not None and is_wall_bead(r.plan):
            out = np.fmin(out, -margins[:, k])
    return out


def is_wall_bead(plan: PassPlan) -> bool:
    """Whether a pass lays a bead against a groove wall (see :func:`fusion_margin_mm`)."""
    if plan.reference in ("left", "right"):
        return True
    if plan.cap:
        return False
    n = plan.beads_in_layer
    return n == 1 or fill_order(n)[min(plan.bead_in_layer, n - 1)] in (0, n - 1)
