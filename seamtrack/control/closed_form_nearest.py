"""The closed forms' branch nearest a configuration, as the arm's control tick wants it: the
branch of :func:`~seamtrack.control.closed_form.ik_branches` that
:func:`nearest_branch` picks (the same numbers), with most
branches never worked out (:func:`ik_nearest`).

A branch's squared distance from the configuration is a sum of one non-negative term per joint;
the same sum with the terms of joints not yet known left out is a lower bound of it (adding
non-negative terms in floating point never lowers a sum). The branch search goes joint 1's
nearer branch first, and skips a branch whose bound already exceeds the best sum found: at
1 kHz the nearest branch is microradians away, the others tenths of a radian.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.control.closed_form import (
    KIND_UR,
    KIND_WRIST,
    U_A2,
    U_A3,
    U_P2I,
    U_P5I,
    U_P6I,
    U_S1,
    U_S4,
    U_S5,
    W_S6,
    ik_branches,
    mul_into,
    nearest_turn,
    pose_at,
    rz_left_into,
    ur_joint_1,
    ur_planar,
    ur_q6,
    wrist_456,
    wrist_elbow,
    wrist_joint_1,
    wrist_links,
    wrist_plane,
    wrist_rotation,
)  # fmt: skip
from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]


@numba.njit(**KERNEL, inline="always")
def _ur_q6(
    q5: float, z1x: float, z1y: float, J6: FloatArray, s4: float, q_near: FloatArray,
    t0: float,
) -> tuple[float, float]:  # fmt: skip
    """:func:`_ur_branches`' joint 6 for joint 5 at ``q5``, and the lower bound of a branch's
    sum of squared differences from ``q_near`` with joints 1, 5 and 6 known (``t0``: joint
    1's term)."""
    q6 = ur_q6(q5, z1x, z1y, J6, s4, q_near[5])
    x4 = nearest_turn(q5, q_near[4]) - q_near[4]
    x5 = nearest_turn(q6, q_near[5]) - q_near[5]
    return q6, (t0 + x4 * x4) + x5 * x5


@numba.njit(**KERNEL, inline="always")
def _keep_nearer(
    d: float, key: int, best: float, best_key: int, row: FloatArray,
    v0: float, v1: float, v2: float, v3: float, v4: float, v5: float,
) -> tuple[float, int]:  # fmt: skip
    """(best, best_key) after a branch (v0 .. v5, ``d`` its squared distance from the seed,
    ``key`` its place in the branches' order): kept in ``row`` when it is nearer than the best
    so far, or as near and earlier (nearest_branch's tiebreak)."""
    if d < best or (d == best and key < best_key):
        row[0], row[1], row[2], row[3], row[4], row[5] = v0, v1, v2, v3, v4, v5
        return d, key
    return best, best_key


@numba.njit(**KERNEL)
def _ur_nearest(
    g: FloatArray, T: FloatArray, q_near: FloatArray, row: FloatArray, ws: FloatArray
) -> bool:
    """The branch of :func:`_ur_branches` that :func:`~seamtrack.control.arm_kernels.
    nearest_branch` picks (the least sum of squared differences from ``q_near``, the first
    of a tie), into ``row``; False where there is none. The same arithmetic per branch, but a
    branch is worked out only where it can still be the nearest: the one nearest in joint 1
    first, then in joints 5 and 6, and a branch skipped once a lower bound of its sum (the
    same sum with the joints not yet known left out: adding the rest can only raise it)
    exceeds the best found. At 1 kHz the nearest branch is microradians away and the others
    tenths of a radian: one branch of eight is worked out. ``ws``: a (6, 4, 4) scratch."""
    reached, psi, k = ur_joint_1(g, T, ws)  # ws: J6, P1i J6, T01^-1 J6, two scratch, A
    if not reached:
        return False
    P2i, P6i, P5i = pose_at(g, U_P2I), pose_at(g, U_P6I), pose_at(g, U_P5I)
    J6 = ws[0]
    a2, a3 = g[U_A2], g[U_A3]
    s1, s4, s5a = g[U_S1], g[U_S4], g[U_S5]
    best = math.inf
    best_key = 8  # the branch's place in _ur_branches' order (i1, i5, i3): a tie's tiebreak
    q1s = (psi + k, psi + math.pi - k)
    first = _nearer_first(q1s, q_near[0])
    for o1 in range(2):
        i1 = first if o1 == 0 else 1 - first
        q1 = q1s[i1]
        r0 = nearest_turn(q1, q_near[0])
        t0 = (r0 - q_near[0]) * (r0 - q_near[0])
        if t0 > best:
            continue
        z1x, z1y = s1 * math.sin(q1), -s1 * math.cos(q1)
        c5 = -(z1x * J6[0, 2] + z1y * J6[1, 2]) / (s4 * s5a)
        if abs(c5) > 1.0 + 1e-12:
            continue
        c5 = min(max(c5, -1.0), 1.0)
        rz_left_into(-q1, ws[1], ws[3])
        mul_into(P2i, ws[3], ws[2])
        q5s = (math.acos(c5), -math.acos(c5))
        q6a, bound_a = _ur_q6(q5s[0], z1x, z1y, J6, s4, q_near, t0)
        q6b, bound_b = _ur_q6(q5s[1], z1x, z1y, J6, s4, q_near, t0)
        first5 = 0 if not bound_b < bound_a else 1
        for o5 in range(2):
            i5 = first5 if o5 == 0 else 1 - first5
            if (bound_a if i5 == 0 else bound_b) > best:
                continue
            q5, q6 = q5s[i5], (q6a if i5 == 0 else q6b)
            reached, q234, x, y, c3 = ur_planar(ws, P6i, P5i, q5, q6, a2, a3)
            if not reached:
                continue
            for i3 in range(2):
                q3 = math.acos(c3) if i3 == 0 else -math.acos(c3)
                q2 = math.atan2(y, x) - math.atan2(a3 * math.sin(q3), a2 + a3 * math.cos(q3))
                v0, v1, v2 = q1, q2, q3
                v3, v4, v5 = q234 - q2 - q3, q5, q6
                v0 = nearest_turn(v0, q_near[0])
                v1 = nearest_turn(v1, q_near[1])
                v2 = nearest_turn(v2, q_near[2])
                v3 = nearest_turn(v3, q_near[3])
                v4 = nearest_turn(v4, q_near[4])
                v5 = nearest_turn(v5, q_near[5])
                d = _plus_squares(0.0, q_near, 0, v0, v1, v2)  # nearest_branch's sum, in order
                d = _plus_squares(d, q_near, 3, v3, v4, v5)
                best, best_key = _keep_nearer(d, 4 * i1 + 2 * i5 + i3, best, best_key, row,
                                              v0, v1, v2, v3, v4, v5)  # fmt: skip
    return best_key < 8


@numba.njit(**KERNEL)
def _wrist_nearest(g: FloatArray, T: FloatArray, q_near: FloatArray, row: FloatArray) -> bool:
    """:func:`_ur_nearest` for the spherical wrist: :func:`_wrist_branches`' arithmetic per
    branch, joint 1's nearer branch first, then the elbow nearer in joints 2 and 3 (its sum so
    far exact), a branch skipped once its sum so far exceeds the best found."""
    ws = np.empty((7, 3, 3))
    reached, beta, k, d = wrist_joint_1(g, T, ws)
    if not reached:
        return False
    l2, l3, g2, g3 = wrist_links(g)
    s6 = g[W_S6]
    best = math.inf
    best_key = 8  # the branch's place in _wrist_branches' order (i1, i3, i6)
    q1s = (beta + k, beta - k)
    first = _nearer_first(q1s, q_near[0])
    for n1 in range(2):
        i1 = first if n1 == 0 else 1 - first
        q1 = q1s[i1]
        v0 = nearest_turn(q1, q_near[0])
        t0 = 0.0
        t0 += (v0 - q_near[0]) * (v0 - q_near[0])
        if t0 > best:
            continue
        inside, px, py, kappa = wrist_plane(g, ws, d, q1, l2, l3)
        if not inside:
            continue
        phis = (g2 - g3 + math.acos(kappa), g2 - g3 - math.acos(kappa))
        q2a, q3a, ta = _wrist_elbow(g, phis[0], px, py, q_near, t0)
        q2b, q3b, tb = _wrist_elbow(g, phis[1], px, py, q_near, t0)
        first3 = 0 if not tb < ta else 1
        for o3 in range(2):
            i3 = first3 if o3 == 0 else 1 - first3
            t12 = ta if i3 == 0 else tb
            if t12 > best:
                continue
            q2, q3 = (q2a, q3a) if i3 == 0 else (q2b, q3b)
            N = wrist_rotation(g, ws, q1, q2, q3)
            sb = math.hypot(N[0, 1], N[0, 2])
            for i6 in range(2):
                sign = 1.0 if i6 == 0 else -1.0
                q4, q5, c6 = wrist_456(N, sb, sign, q_near[3])
                v1, v2 = nearest_turn(q2, q_near[1]), nearest_turn(q3, q_near[2])
                v3, v4 = nearest_turn(q4, q_near[3]), nearest_turn(q5, q_near[4])
                v5 = nearest_turn(s6 * c6, q_near[5])
                # nearest_branch's sum, in its order (joints 1-3 in t12)
                dd = _plus_squares(t12, q_near, 3, v3, v4, v5)
                best, best_key = _keep_nearer(dd, 4 * i1 + 2 * i3 + i6, best, best_key, row,
                                              v0, v1, v2, v3, v4, v5)  # fmt: skip
    return best_key < 8


@numba.njit(**KERNEL, inline="always")
def _plus_squares(total: float, q_near: FloatArray, j: int, a: float, b: float, c: float) -> float:
    """``total`` plus the squared differences of ``a``, ``b``, ``c`` from joints ``j``,
    ``j + 1``, ``j + 2`` of ``q_near``, added in that order (nearest_branch's sum)."""
    total += (a - q_near[j]) * (a - q_near[j])
    total += (b - q_near[j + 1]) * (b - q_near[j + 1])
    total += (c - q_near[j + 2]) * (c - q_near[j + 2])
    return total


@numba.njit(**KERNEL, inline="always")
def _nearer_first(q1s: tuple[float, float], q_near: float) -> int:
    """Which of joint 1's two solutions lies nearer ``q_near`` (whole turns aside; 0 on a
    tie): the branches through it are worked out first."""
    x0 = nearest_turn(q1s[0], q_near) - q_near
    x1 = nearest_turn(q1s[1], q_near) - q_near
    return 0 if not x1 * x1 < x0 * x0 else 1


@numba.njit(**KERNEL, inline="always")
def _wrist_elbow(
    g: FloatArray, phi3: float, px: float, py: float, q_near: FloatArray, t0: float
) -> tuple[float, float, float]:  # fmt: skip
    """:func:`~seamtrack.control.closed_form.wrist_elbow`'s joints 2 and 3 for the elbow at
    ``phi3``, and the sum of squared differences from ``q_near`` over joints 1-3 (``t0``:
    joint 1's, in nearest_branch's order)."""
    q2, q3 = wrist_elbow(g, phi3, px, py)
    x1 = nearest_turn(q2, q_near[1]) - q_near[1]
    x2 = nearest_turn(q3, q_near[2]) - q_near[2]
    return q2, q3, (t0 + x1 * x1) + x2 * x2


@numba.njit(**KERNEL)
def nearest_branch(branches: FloatArray, count: int, q_near: FloatArray) -> int:
    """The branch (row of ``branches``, already turned by whole turns towards ``q_near``)
    nearest ``q_near`` (sum of squared joint differences); -1 if none."""
    best, best_d = -1, math.inf
    for b in range(count):
        d = 0.0
        for j in range(q_near.shape[0]):
            x = branches[b, j] - q_near[j]
            d += x * x
        if d < best_d:
            best, best_d = b, d
    return best


@numba.njit(**KERNEL)
def ik_nearest(
    kind: int, g: FloatArray, T: FloatArray, q_near: FloatArray, row: FloatArray
) -> bool:
    """The closed-form branch of the torch pose ``T`` nearest ``q_near`` into ``row`` (the
    row of :func:`ik_branches` that :func:`nearest_branch`
    picks, the same numbers); False where there is none: by :func:`_ur_nearest` and
    :func:`_wrist_nearest` (most branches not worked out), else from all branches."""
    return ik_nearest_in(kind, g, T, q_near, row, np.empty((6, 4, 4)))


@numba.njit(**KERNEL)
def ik_nearest_in(
    kind: int, g: FloatArray, T: FloatArray, q_near: FloatArray, row: FloatArray,
    ws: FloatArray,
) -> bool:  # fmt: skip
    """:func:`ik_nearest` with a (6, 4, 4) scratch ``ws`` (the arm tick's)."""
    if kind == KIND_UR:
        return _ur_nearest(g, T, q_near, row, ws)
    if kind == KIND_WRIST:
        return _wrist_nearest(g, T, q_near, row)
    branches = np.empty((8, q_near.shape[0]))
    count = ik_branches(kind, g, T, q_near, branches)
    best = nearest_branch(branches, count, q_near)
    if best < 0:
        return False
    row[:] = branches[best]
    return True
