"""User-facing errors: each names the field at fault and the fix.

The CLI prints ``str(error)`` as one line and exits with code 2; library users
catch :class:`SeamtrackError` (or a subclass) and read ``.field`` and ``.fix``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple


class SeamtrackError(Exception):
    """An error caused by the user's input, with the field at fault and a fix.

    Parameters
    ----------
    message : str
        What is wrong, in the user's terms.
    field : str, optional
        Dotted path of the offending field (``"sensor.frame_rate_hz"``) or a file name.
    fix : str, optional
        What to do about it.
    """

    def __init__(self, message: str, *, field: str | None = None, fix: str | None = None):
        super().__init__(message)
        self.message = message
        self.field = field
        self.fix = fix

    def __str__(self) -> str:
        text = f"{self.field}: {self.message}" if self.field else self.message
        if self.fix:
            text += f"; fix: {self.fix}"
        return " ".join(text.split())


class SceneError(SeamtrackError):
    """A scene file (or an override) that cannot be used."""


class Rule(NamedTuple):
    """One row of a validation table: ``broken`` where the input fails it, and the error's
    ``message``, ``field`` and ``fix`` (see :func:`check_rules`)."""

    broken: bool
    message: str
    field: str
    fix: str


def check_rules(rules: Iterable[Rule], error: type[SeamtrackError] = SceneError) -> None:
    """Raise ``error`` for the first broken rule of a validation table (in its order)."""
    for rule in rules:
        if rule.broken:
            raise error(rule.message, field=rule.field, fix=rule.fix)


class SensorGeometryError(SeamtrackError):
    """Sensor parameters that describe no physical triangulation sensor."""


class SeamError(SeamtrackError):
    """Seam points that cannot define a seam (NaN, too few, repeated)."""


class ReachError(SeamtrackError):
    """Something the robot has to reach lies outside its position limits."""


class WorkpieceError(SeamtrackError):
    """A CAD script, STEP file, selector or mesh that cannot be used."""


class PluginError(SeamtrackError):
    """A user tracker or extractor that cannot be imported or lacks the protocol."""


class OutputError(SeamtrackError):
    """An output location that cannot be written."""


class PluginRuntimeError(SeamtrackError):
    """User code (a tracker, an extractor) that raised, or returned what it must not, during a
    run. ``str()`` is the one line; :meth:`user_frames` the traceback of the user's own code."""

    def __init__(
        self,
        message: str,
        *,
        field: str | None = None,
        fix: str | None = None,
        error: BaseException | None = None,
    ):
        super().__init__(message, field=field, fix=fix)
        self.error = error

    def user_frames(self, all_frames: bool = False) -> str:
        """The traceback of the exception, without seamtrack's own frames unless asked."""
        import os
        import traceback

        if self.error is None:
            return ""
        package = os.path.dirname(os.path.abspath(__file__)) + os.sep
        frames = [
            f
            for f in traceback.extract_tb(self.error.__traceback__)
            if all_frames or not os.path.abspath(f.filename).startswith(package)
        ]
        return "".join(traceback.format_list(frames))


def plugin_failed(
    field: str, name: str, method: str, t_s: float, error: BaseException
) -> PluginRuntimeError:
    """The error for ``error`` raised inside a plugin's ``method`` at simulated time ``t_s``."""
    return PluginRuntimeError(
        f"{name!r} {method}() raised at t = {t_s:.6g} s: {type(error).__name__}: {error}",
        field=field,
        fix="fix the plugin (its own frames follow; --debug shows seamtrack's too)",
        error=error,
    )
