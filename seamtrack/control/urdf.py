"""A user's URDF file, read and checked before Pinocchio sees it.

Pinocchio parses URDF with urdfdom, a C++ library that prints its own ``Error:`` lines on the
process's stderr (file descriptor 2, past Python's ``sys.stderr``) before it raises, and that
builds whatever chain it is given. So :func:`read_urdf` reads a bounded number of bytes from a
regular file only, and :func:`check_urdf` checks on the XML (Python's ``xml.etree``, which
resolves no external entity; a URDF has no DTD, so entity declarations are refused outright)
what urdfdom would complain about or what would make a chain too large: every joint's parent and
child, origin, axis and limits, one root link, the number of joints. :func:`quiet_c_stderr`
keeps what urdfdom still prints off the terminal (it joins our own error line instead).
"""

from __future__ import annotations

import math
import os
import stat
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

from seamtrack.errors import SceneError

#: The largest URDF file read (bytes). A serial arm's kinematics take a few kB; a URDF with
#: inertias, visuals and collision geometry of every link some tens of kB (meshes are files of
#: their own). Anything larger is not an arm's description.
MAX_URDF_BYTES = 4 * 2**20

#: The most movable joints a URDF may have. A welding arm has 6 or 7; a track or a gantry that
#: carries it, and a 2-axis positioner, add a few more (rarely beyond 12). 32 leaves room for any
#: such cell, while a chain of hundreds of joints (gigabytes in the inverse kinematics) is not
#: a robot but a generated or broken file.
MAX_JOINTS = 32

#: The most joints of any type (fixed ones included: frames for tools, sensors, mounts).
MAX_ALL_JOINTS = 4 * MAX_JOINTS

#: Joint types urdfdom knows; seamtrack's arms use revolute and prismatic ones (and fixed).
_MOVABLE = ("revolute", "prismatic")
_UNSUPPORTED = ("continuous", "floating", "planar")


def _refuse(what: str, message: str, fix: str, field: str) -> SceneError:
    return SceneError(f"{what}: {message}", field=field, fix=fix)


def read_urdf(path: str | Path, field: str = "robot.urdf") -> str:
    """The text of a URDF file: a regular file of at most :data:`MAX_URDF_BYTES`, UTF-8."""
    path = Path(path)
    fix = "give the path of a URDF file (relative to the scene file)"
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            kind = "a folder" if stat.S_ISDIR(info.st_mode) else "a device, pipe or socket"
            raise _refuse(repr(str(path)), f"is {kind}, not a regular file", fix, field)
        with path.open("rb") as handle:
            data = handle.read(MAX_URDF_BYTES + 1)
        if len(data) > MAX_URDF_BYTES:
            raise _refuse(
                repr(str(path)),
                f"is larger than {MAX_URDF_BYTES // 2**20} MiB, far beyond any arm's URDF",
                "give the URDF of one serial arm (meshes stay in files of their own)",
                field,
            )
        return data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(
            f"cannot read URDF {str(path)!r}: {getattr(exc, 'strerror', None) or exc}",
            field=field,
            fix=fix,
        ) from None


def _floats(element: Any, attribute: str, count: int) -> list[float] | None:
    """The attribute's numbers (None: absent); a SceneError-worthy ValueError if malformed."""
    text = element.get(attribute)
    if text is None:
        return None
    values = [float(x) for x in text.split()]
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ValueError(f'<{element.tag} {attribute}="{text}"> must be {count} finite numbers')
    return values


class _Finding(Exception):
    """What a check of :func:`check_urdf` found wrong, and the fix (the caller names the file
    and the scene's field)."""

    def __init__(self, message: str, fix: str) -> None:
        super().__init__(message)
        self.message, self.fix = message, fix


_A_URDF = "give a URDF file (XML with a <robot> element)"


def check_urdf(text: str, what: str, field: str = "robot.urdf") -> None:
    """Refuse, naming ``field``, a URDF that urdfdom would reject (with its own stderr lines) or
    that is too large a chain: see the module's docstring."""
    try:
        root = _robot(text)
        links = [link.get("name") for link in root.findall("link")]
        joints = root.findall("joint")
        _check_sizes(links, joints)
        children: set[str] = set()
        for index, joint in enumerate(joints):
            child = _checked_joint(joint, joint.get("name") or f"number {index + 1}", links)
            if child in children:
                raise _Finding(
                    f"joint {joint.get('name') or f'number {index + 1}'!r}: link {child!r} is "
                    "the child of two joints",
                    "give every link one parent joint (a serial chain)",
                )
            children.add(child)
        roots = [link for link in links if link not in children]
        if len(roots) != 1:
            raise _Finding(
                f"has {len(roots)} root links ({', '.join(map(str, roots[:4]))}): a serial "
                "arm's links hang from one base link",
                "attach every link to the chain by a joint (or remove the ones not attached)",
            )
    except _Finding as finding:
        raise _refuse(what, finding.message, finding.fix, field) from None


def _robot(text: str) -> ElementTree.Element:
    """The ``<robot>`` element of a URDF's text, parsed without DTDs or entities."""
    if "<robot" not in text:
        raise _Finding("is not a URDF: no <robot> element", _A_URDF)
    if "<!ENTITY" in text or "<!DOCTYPE" in text:
        raise _Finding(
            "declares a DTD or entities, which a URDF never needs",
            "remove the <!DOCTYPE ...> and <!ENTITY ...> declarations",
        )
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise _Finding(
            f"does not parse as a URDF: not well-formed XML ({exc})",
            "check the file's XML (every element closed, quotes matched)",
        ) from None
    if root.tag != "robot":
        raise _Finding(f"its root element is <{root.tag}>, not <robot>", _A_URDF)
    return root


def _check_sizes(links: list[str | None], joints: list[ElementTree.Element]) -> None:
    """At most :data:`MAX_JOINTS` movable joints and :data:`MAX_ALL_JOINTS` in all; every link
    named once."""
    movable = sum(joint.get("type") in (*_MOVABLE, *_UNSUPPORTED) for joint in joints)
    if movable > MAX_JOINTS:
        raise _Finding(
            f"has {movable} movable joints, more than {MAX_JOINTS} (a welding arm has 6 or 7; "
            "a track and a positioner add a few)",
            f"give one serial arm of at most {MAX_JOINTS} joints",
        )
    if len(joints) > MAX_ALL_JOINTS:
        raise _Finding(
            f"has {len(joints)} joints, more than {MAX_ALL_JOINTS}",
            f"give one serial arm (at most {MAX_JOINTS} movable joints)",
        )
    if None in links or len(set(links)) != len(links):
        raise _Finding(
            "every <link> needs a name, each name used once", 'give each link a unique name="..."'
        )


def _checked_joint(joint: ElementTree.Element, name: str, links: list[str | None]) -> str:
    """Check one ``<joint>`` (its type, its two links, its numbers); its child link's name."""
    kind = joint.get("type")
    where = f"joint {name!r}"
    if kind in _UNSUPPORTED:
        raise _Finding(
            f"{where} is {kind}: seamtrack needs a range for every joint (a {kind} joint has none)",
            'make it type="revolute" or "prismatic" with <limit lower="..." upper="..." '
            'velocity="..." effort="..."/>',
        )
    if kind not in (*_MOVABLE, "fixed"):
        raise _Finding(f"{where} has type {kind!r}", "use revolute, prismatic or fixed")
    ends = [joint.find(tag) for tag in ("parent", "child")]
    names = [None if end is None else end.get("link") for end in ends]
    for tag, link in zip(("parent", "child"), names, strict=True):
        if link is None or link not in links:
            raise _Finding(
                f"{where}: its <{tag} link=...> names no <link> of the file",
                f"give the {tag} link's name, declared as <link name=...>",
            )
    try:
        _check_numbers(joint, kind)
    except ValueError as exc:
        raise _Finding(
            f"{where}: {exc}",
            'give finite numbers: <origin xyz="x y z" rpy="r p y"/>, <axis xyz="x y z"/>, '
            "<limit lower upper velocity effort/>",
        ) from None
    return str(names[1])


def _check_numbers(joint: ElementTree.Element, kind: str | None) -> None:
    """The joint's origin, axis and limits are finite numbers, its axis a direction."""
    origin = joint.find("origin")
    if origin is not None:
        _floats(origin, "xyz", 3)
        _floats(origin, "rpy", 3)
    axis = joint.find("axis")
    vector = None if axis is None else _floats(axis, "xyz", 3)
    if vector is not None and not any(vector):
        raise ValueError('axis xyz="0 0 0" has no direction')
    if kind in _MOVABLE:
        limit = joint.find("limit")
        if limit is None:
            raise ValueError("a revolute or prismatic joint needs a <limit>")
        for attribute in ("lower", "upper", "velocity", "effort"):
            if _floats(limit, attribute, 1) is None:
                raise ValueError(f"its <limit> has no {attribute}")


@contextmanager
def quiet_c_stderr() -> Iterator[list[str]]:
    """File descriptor 2 goes to a temporary file while the block runs (urdfdom writes there,
    past ``sys.stderr``); the list yielded holds those lines when the block ends."""
    sys.stderr.flush()
    saved = os.dup(2)
    lines: list[str] = []
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        try:
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            lines += tmp.read(65536).decode("utf-8", "replace").splitlines()
