"""The Gymnasium environment: ``import seamtrack.gym`` registers ``seamtrack/Scene-v0``.

>>> import gymnasium, seamtrack.gym
>>> env = gymnasium.make("seamtrack/Scene-v0", scene="paper-v-groove",
...                      overrides={"workpiece.params.seam_length_mm": 100.0})

One step is one sensor frame; see :mod:`seamtrack.gym.env` for the spaces, the reward and the
episode's end, and docs/gym.md for a walk-through. Needs the ``gym`` extra:
``pip install 'seamtrack[gym]'``.
"""

from __future__ import annotations

from seamtrack.errors import SeamtrackError


class GymnasiumMissing(SeamtrackError, ImportError):
    """The ``gym`` extra (``gymnasium``, ``greenlet``) is not installed (an ``ImportError``
    too)."""


try:
    import greenlet  # noqa: F401  (the loop's coroutine: seamtrack.gym.lockstep)
    import gymnasium
except ImportError as exc:
    raise GymnasiumMissing(
        f"{exc.name or 'gymnasium'} is not installed",
        field="seamtrack.gym",
        fix="pip install 'seamtrack[gym]'",
    ) from None

from seamtrack.gym.env import (  # noqa: E402
    TORCH_STATE,
    BadActionWarning,
    SeamTrackEnv,
    split_observation,
)
from seamtrack.gym.policies import ProfilePD  # noqa: E402
from seamtrack.gym.vector import BatchedVectorEnv  # noqa: E402

#: The environment ids ``import seamtrack.gym`` registers.
ENV_IDS = ("seamtrack/Scene-v0",)

if "seamtrack/Scene-v0" not in gymnasium.registry:  # a re-import must not warn
    gymnasium.register(
        id="seamtrack/Scene-v0",
        entry_point="seamtrack.gym.env:SeamTrackEnv",
        vector_entry_point="seamtrack.gym.vector:BatchedVectorEnv",
        disable_env_checker=False,
    )

__all__ = [
    "ENV_IDS",
    "TORCH_STATE",
    "BadActionWarning",
    "BatchedVectorEnv",
    "GymnasiumMissing",
    "ProfilePD",
    "SeamTrackEnv",
    "split_observation",
]
