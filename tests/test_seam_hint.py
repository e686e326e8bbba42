"""The tracker's prior (a :class:`~seamtrack.sensing.profiles.SeamHint`) in the extractor
protocol: the v-groove extractor takes the V nearest the expected seam point, never a V that is
not there, and without a hint answers as before; extractors written without a ``hint`` still
run; the arm scenes' mitred corner within 0.5 mm."""

from __future__ import annotations

import numpy as np
import pytest

import seamtrack as st
from seamtrack.features.vgroove.extractor import VGrooveExtractor
from seamtrack.sensing.profiles import Feature, Profile, SeamHint, hint_from_path
from seamtrack.simulation.assemble import takes_hint

PLATE_Z = 90.0  # mm from the sensor


def _two_vs() -> tuple[Profile, np.ndarray, np.ndarray]:
    """A plate with two V's: a deep one (apex (-5, 93)) and a shallower one (apex (5, 91.5)),
    60 deg included each, sampled every 0.05 mm; and their apexes, the analytic truth."""
    half = np.tan(np.radians(30.0))  # half-width per mm of depth
    deep, shallow = np.array([-5.0, PLATE_Z + 3.0]), np.array([5.0, PLATE_Z + 1.5])
    y = np.arange(-12.0, 12.0, 0.05)
    z = np.full_like(y, PLATE_Z)
    for ay, az in (deep, shallow):
        depth = az - PLATE_Z
        z = np.maximum(z, az - np.abs(y - ay) / half * 1.0 * (depth > 0))
        z = np.where(np.abs(y - ay) <= depth * half, np.maximum(z, az - np.abs(y - ay) / half), z)
    return Profile(np.column_stack([y, z]), T_world_sensor=np.eye(4)), deep, shallow


EXTRACT = VGrooveExtractor(min_explained=0.0)


def test_without_a_hint_the_answer_is_unchanged_and_the_best_supported_v() -> None:
    profile, deep, _ = _two_vs()
    plain, none = EXTRACT(profile), EXTRACT(profile, hint=None)
    assert plain and none
    assert np.array_equal(plain.point_laser, none.point_laser)  # bit-identical
    assert plain.confidence == none.confidence
    assert np.hypot(*(plain.point_laser - deep)) < 0.05  # the deeper V: more wall on its lines


def test_the_hint_picks_the_v_that_continues_the_seam() -> None:
    profile, deep, shallow = _two_vs()
    hint = SeamHint((4.6, PLATE_Z + 1.4))  # a tracker following the shallow V
    found = EXTRACT(profile, hint=hint)
    assert found and np.hypot(*(found.point_laser - shallow)) < 0.05
    near_deep = EXTRACT(profile, hint=SeamHint((-5.3, PLATE_Z + 3.1)))
    assert near_deep and np.hypot(*(near_deep.point_laser - deep)) < 0.05


def test_a_hint_where_no_v_is_invents_none() -> None:
    """A hint between the V's, outside both tolerances: the best-supported V, as without one;
    never the hinted point itself."""
    profile, deep, _ = _two_vs()
    found = EXTRACT(profile, hint=SeamHint((0.0, PLATE_Z)))
    assert found and np.array_equal(found.point_laser, EXTRACT(profile).point_laser)
    assert np.hypot(*(found.point_laser - deep)) < 0.05


def test_hint_from_path_crosses_the_laser_plane() -> None:
    """A path along world x through (-3, 1, 90) crosses a laser plane x = 0 (sensor at the
    world's origin, axes aligned) at y = 1, z = 90."""
    hint = hint_from_path(np.eye(4), [-3.0, 1.0, 90.0], [2.0, 0.0, 0.0])
    assert hint is not None and hint.point_laser == pytest.approx((1.0, 90.0))
    assert hint.direction == pytest.approx((1.0, 0.0, 0.0))
    assert hint_from_path(np.eye(4), [0.0, 1.0, 90.0], [0.0, 1.0, 0.0]) is None  # in the plane


def _old_style(profile: Profile) -> Feature:
    """A user's extractor written before the hint: one parameter."""
    return VGrooveExtractor(min_explained=0.0)(profile)


def test_an_extractor_without_hint_is_called_as_before() -> None:
    assert not takes_hint(_old_style)
    assert takes_hint(EXTRACT)
    assert takes_hint(lambda profile, **kw: None)


OLD_STYLE = """
from seamtrack.features.vgroove.extractor import VGrooveExtractor

CALLS = []


class OldStyle:
    name = "old-style"

    def __init__(self, **params):
        self.inner = VGrooveExtractor(**params)

    def __call__(self, profile):
        CALLS.append(1)
        return self.inner(profile)
"""


def test_a_user_extractor_without_hint_runs_in_the_loop(tmp_path, monkeypatch) -> None:
    """A user's extractor class without ``hint``, named as the scene's extractor, runs a
    tracked mesh scene to the end (the trajectory tracker gives hints; they are not passed)."""
    (tmp_path / "old_style_extractor.py").write_text(OLD_STYLE)
    monkeypatch.syspath_prepend(str(tmp_path))
    import importlib

    module = importlib.import_module("old_style_extractor")
    s = st.simulate(
        st.load_scene(
            "paper-v-groove",
            overrides={
                "extractor.name": "old_style_extractor:OldStyle",
                "workpiece.params.seam_length_mm": 20.0,
            },
        )
    ).summary
    assert module.CALLS and s["status"] == "completed"
    assert s["max_error_mm"] <= 0.2


@pytest.mark.slow
@pytest.mark.parametrize(
    "robot",
    [{}, {"robot.model": "ur10e", "robot.base_origin_mm": [-600.0, 0.0, -300.0]}],
    ids=["kr16", "ur10e"],
)
def test_the_mitred_corner_within_half_a_millimetre_on_both_arms(robot) -> None:
    """The laser plane crosses both grooves at the mitre: with the tracker's hint the torch
    stays within 0.5 mm of the CAD seam all the way (1.30 mm without it)."""
    s = st.simulate(st.load_scene("v-groove-corner-arm", overrides=robot)).summary
    assert s["status"] == "completed"
    assert s["max_error_mm"] <= 0.5


def test_the_tracker_is_asked_for_a_hint_only_for_an_extractor_that_uses_one() -> None:
    """The v-groove chooses among V's with the hint; the fillet ignores it. On the fillet's
    arm scene the loop does not ask the tracker for a hint, and the run is the same, byte for
    byte, as one that asks and hands it on (the hint never reaches the answer)."""
    import dataclasses

    from seamtrack.features.extractors import extractor
    from seamtrack.simulation.assemble import build_parts, uses_hint
    from seamtrack.simulation.loop import run

    assert uses_hint(extractor("v-groove")) and not uses_hint(extractor("fillet"))
    assert uses_hint(lambda profile, hint=None: None)  # a user's: it may use it
    parts = build_parts(st.load_scene("pipe-saddle", {"simulation.time_limit_s": 1.0}))
    assert not parts.sense_uses_hint
    asked = []
    hint = parts.tracker.hint

    def counting(T_world_sensor):
        asked.append(1)
        return hint(T_world_sensor)

    object.__setattr__(parts.tracker, "hint", counting)
    try:
        plain = run(parts)
        assert not asked
        forced = run(dataclasses.replace(parts, sense_uses_hint=True))
    finally:
        del parts.tracker.hint
    assert len(asked) == forced.summary["frames"]  # asked at every frame
    for name in ("tcp_world", "target_world", "error_mm", "joints_rad"):
        a, b = getattr(plain.trace, name), getattr(forced.trace, name)
        assert a.tobytes() == b.tobytes(), name
    assert plain.trace.frames.keys() == forced.trace.frames.keys()
    for name, a in plain.trace.frames.items():
        assert a.tobytes() == forced.trace.frames[name].tobytes(), name


NAN_POINT = """
import numpy as np
from seamtrack.sensing.profiles import Feature


class NanPoint:
    name = "nan-point"

    def __call__(self, profile):
        return Feature(point_laser=np.array([np.nan, 90.0]), confidence=1.0)
"""


def test_a_user_extractor_returning_a_nan_point_is_refused_by_name(tmp_path, monkeypatch):
    """A seam point that is not finite stops the run with the extractor named (not a NaN
    fed to the tracker)."""
    from seamtrack.errors import PluginRuntimeError

    (tmp_path / "nan_point_extractor.py").write_text(NAN_POINT)
    monkeypatch.syspath_prepend(str(tmp_path))
    scene = st.load_scene(
        "paper-v-groove",
        overrides={
            "extractor.name": "nan_point_extractor:NanPoint",
            "workpiece.params.seam_length_mm": 20.0,
        },
    )
    with pytest.raises(PluginRuntimeError, match="returned the seam point") as info:
        st.simulate(scene)
    assert info.value.field == "extractor.name"
