"""A refusal: why a step of an extractor (the front end, the segmentation, a joint model) found
nothing, as a typed result the caller tests with ``isinstance(x, Refusal)``; its ``reason`` is
the message the failed :class:`~seamtrack.sensing.profiles.Feature` carries."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Refusal:
    """Why nothing was found (``reason``: one sentence, as ``Feature.reason``)."""

    reason: str
