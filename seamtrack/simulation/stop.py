"""Why a run stops: a :class:`StopRequest` the loop checks between ticks, and the one place
that turns the way a run ended into its summary's ``status``, ``stop_cause`` and
``stop_reason``.

Anyone may ask a running loop to stop: a signal handler (``seamtrack run`` on SIGINT and
SIGTERM), a bridge whose client went away, a Gymnasium env, a notebook. They call
:meth:`StopRequest.request` with a cause and a sentence; the loop sees it at its next tick
(a compiled stretch of ticks returns at every sensor frame), stops there, and scores what was
simulated up to the stop with the status ``interrupted``. A request only sets fields: it is
safe from a signal handler, which must never raise into compiled code.

The loop's own ends go through the same record (:meth:`StopRequest.end`), and
:func:`outcome` alone names them:

=====================  ==================  ============================================
how the run ended       ``status``          ``stop_cause``
=====================  ==================  ============================================
a request from outside  ``interrupted``     the requester's cause (``sigint``, ...)
a bridge's client fails ``stalled``         ``bridge_failure`` (a request with a status)
target out of travel    ``limit_violation`` ``limit_violation``
no progress             ``stalled``         ``stalled``
simulated-time limit    ``stalled``         ``time_limit``
wall-clock limit        ``stalled``         ``wall_time_limit``
torch at rest, no seam  ``completed`` /     ``closed_seam``, the tracker's own cause,
                        ``lost_seam``       ``seam_lost_at_end`` or ``lost_seam``
=====================  ==================  ============================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: The status of a run stopped from outside (a signal, a bridge, a caller).
INTERRUPTED = "interrupted"


@dataclass
class StopRequest:
    """A request to end a run, with its cause and a sentence for ``stop_reason``.

    ``status`` is empty until someone asks; :meth:`request` (from outside) keeps the first
    request, so a second signal does not rename the first one's stop.
    """

    status: str = ""
    cause: str = ""
    reason: str = ""

    @property
    def requested(self) -> bool:
        return bool(self.status)

    def request(self, cause: str, reason: str = "", status: str = INTERRUPTED) -> None:
        """Ask the loop to stop at its next tick (status ``interrupted`` unless the requester
        names another, as a bridge whose client failed does: ``stalled``); safe in a signal
        handler. The first request wins."""
        if not self.status:
            self.cause, self.reason = cause, reason or cause
            self.status = status

    def end(self, status: str, reason: str = "", cause: str = "") -> None:
        """The loop's own end (``limit_violation``, ``stalled``, ``completed``, ...)."""
        self.status, self.reason, self.cause = status, reason, cause


def outcome(stop: StopRequest, closed: bool, tracker_cause: Any) -> tuple[str, str, str]:
    """``(status, stop_reason, stop_cause)`` of a run that ended as ``stop`` records (the
    table in the module docstring): ``closed`` is a girth seam's, ``tracker_cause`` the
    tracker's own ``stop_cause`` (``end_of_part``, ``seam_end``) if it has one."""
    status, reason = stop.status, stop.reason
    if stop.cause:
        return status, reason, stop.cause
    if status in ("stalled", "limit_violation"):
        return status, reason, status
    if closed and status == "completed":
        return status, reason, "closed_seam"
    if isinstance(tracker_cause, str) and tracker_cause:
        return status, reason, tracker_cause
    return status, reason, "seam_lost_at_end" if status == "completed" else "lost_seam"
