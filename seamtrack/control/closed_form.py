"""Closed-form inverse kinematics of the arms that have one, read from their URDF.

Two families, recognised from the chain Pinocchio reads from the URDF (never from a table of
numbers copied in):

- **UR family** (:data:`KIND_UR`): six revolute joints about their frames' z axes, each fixed
  placement a Denavit-Hartenberg link ``Tz(d) Tx(a) Rx(alpha)`` (URDF origin ``xyz = (a, 0,
  d)``, ``rpy = (alpha, 0, 0)``) with alpha = +-90 deg after joints 1, 4 and 5 and 0 after
  joints 2 and 3, and no a after joints 1, 4, 5: shoulder, elbow and wrist 1 parallel, as on
  every Universal Robots arm. The standard analytic solution (the one of Hawkins, "Analytic
  inverse kinematics for the Universal Robots UR-5/UR-10 arms", 2013, in these DH terms): the
  wrist-2 point's offset from the plane of the parallel axes gives joint 1 (two branches), the
  tool axis then gives joint 5 (two) and joint 6, and the remaining planar 3R chain gives
  joints 2, 3 (elbow up or down) and 4: 8 branches.
- **Spherical wrist** (:data:`KIND_WRIST`, the KUKA KR 16 and most 6R industrial arms): the
  axes of joints 4, 5 and 6 meet in one point (the wrist centre), axis 5 at right angles to
  the other two, which are parallel in the zero pose; axes 2 and 3 parallel and at right
  angles to axis 1. The wrist centre's position gives joints 1 to 3 (shoulder front or back,
  elbow up or down), the orientation left for the wrist gives joints 4 to 6 as Euler angles
  about its axes (wrist flipped or not): 8 branches. Everything is measured on the chain in
  its zero pose (product of exponentials), so any signs of the axes and offsets work.

:func:`closed_form_of` checks the URDF against a family's assumptions (axes, offsets,
intersections, to 1e-9) and then proves the solution on seeded random poses (every branch's
forward kinematics back on the pose within 1e-9 mm, the drawn joints among the branches);
an arm that passes neither keeps the iterative solver. Branches are returned each joint
turned by whole turns to the nearest of a given configuration; at a singularity (wrist axes
aligned, joint 5 at 0 or 180 deg) the joint 4 of that configuration is kept.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]

#: Which solver an arm's inverse kinematics uses.
KIND_NONE, KIND_UR, KIND_WRIST = 0, 1, 2
KIND_NAMES = {KIND_NONE: "iterative", KIND_UR: "UR closed form", KIND_WRIST: "spherical wrist"}

#: Geometric checks of a family's assumptions (unit vectors, metres).
GEOMETRY_TOL = 1e-9

#: |sin| of joint 5 below which the wrist is treated as singular (joint 4 kept).
SINGULAR_SIN = 1e-10

_TWO_PI = 2.0 * math.pi


@numba.njit(**KERNEL)
def nearest_turn(x: float, ref: float) -> float:
    """x turned by whole turns to the nearest of ``ref``."""
    return x + _TWO_PI * round((ref - x) / _TWO_PI)


@numba.njit(**KERNEL)
def mul(A: FloatArray, B: FloatArray) -> FloatArray:
    """A @ B for small matrices, in loops (no BLAS call: a 4 x 4 product in ~30 ns)."""
    n, m, p = A.shape[0], A.shape[1], B.shape[1]
    out = np.zeros((n, p))
    for i in range(n):
        for k in range(m):
            a = A[i, k]
            for j in range(p):
                out[i, j] += a * B[k, j]
    return out


@numba.njit(**KERNEL)
def mul_into(A: FloatArray, B: FloatArray, out: FloatArray) -> None:
    """out = A @ B for small square matrices (no allocation; ``out`` not A or B)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            x = 0.0
            for k in range(n):
                x += A[i, k] * B[k, j]
            out[i, j] = x


@numba.njit(**KERNEL)
def _tmul_into(A: FloatArray, B: FloatArray, out: FloatArray) -> None:
    """out = A.T @ B for 3 x 3 matrices."""
    for i in range(3):
        for j in range(3):
            out[i, j] = A[0, i] * B[0, j] + A[1, i] * B[1, j] + A[2, i] * B[2, j]


@numba.njit(**KERNEL)
def rz_left_into(q: float, A: FloatArray, out: FloatArray) -> None:
    """out = Rz(q) @ A (4 x 4)."""
    c, s = math.cos(q), math.sin(q)
    for j in range(4):
        a0, a1 = A[0, j], A[1, j]
        out[0, j] = c * a0 - s * a1
        out[1, j] = s * a0 + c * a1
        out[2, j], out[3, j] = A[2, j], A[3, j]


@numba.njit(**KERNEL)
def _rz_right(A: FloatArray, q: float, out: FloatArray) -> None:
    """out = A @ Rz(q) (4 x 4)."""
    c, s = math.cos(q), math.sin(q)
    for i in range(4):
        a0, a1 = A[i, 0], A[i, 1]
        out[i, 0] = a0 * c + a1 * s
        out[i, 1] = -a0 * s + a1 * c
        out[i, 2], out[i, 3] = A[i, 2], A[i, 3]


@numba.njit(**KERNEL, inline="always")
def rodrigues_into(x: float, y: float, z: float, angle: float, out: FloatArray) -> None:
    """``out`` (3, 3) = the rotation by ``angle`` about the unit axis (x, y, z) (Rodrigues)."""
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    out[0, 0], out[0, 1], out[0, 2] = c + t * x * x, t * x * y - s * z, t * x * z + s * y
    out[1, 0], out[1, 1], out[1, 2] = t * x * y + s * z, c + t * y * y, t * y * z - s * x
    out[2, 0], out[2, 1], out[2, 2] = t * x * z - s * y, t * y * z + s * x, c + t * z * z


@numba.njit(**KERNEL)
def _rot_into(axis: FloatArray, angle: float, out: FloatArray) -> None:
    rodrigues_into(axis[0], axis[1], axis[2], angle, out)


@numba.njit(**KERNEL)
def _rz(q: float) -> FloatArray:
    out = np.eye(4)
    c, s = math.cos(q), math.sin(q)
    out[0, 0], out[0, 1], out[1, 0], out[1, 1] = c, -s, s, c
    return out


@numba.njit(**KERNEL)
def _rot(axis: FloatArray, angle: float) -> FloatArray:
    x, y, z = axis[0], axis[1], axis[2]
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    out = np.empty((3, 3))
    out[0, 0], out[0, 1], out[0, 2] = c + t * x * x, t * x * y - s * z, t * x * z + s * y
    out[1, 0], out[1, 1], out[1, 2] = t * x * y + s * z, c + t * y * y, t * y * z - s * x
    out[2, 0], out[2, 1], out[2, 2] = t * x * z - s * y, t * y * z + s * x, c + t * z * z
    return out


# Layout of the UR parameters: four 4 x 4 matrices, then scalars.
U_P2I, U_P1I, U_P6I, U_P5I, U_TCP = 0, 16, 32, 48, 64
U_A2, U_A3, U_DLAT, U_S1, U_S4, U_S5 = 80, 81, 82, 83, 84, 85
UR_FIELDS = 86


@numba.njit(**KERNEL)
def pose_at(g: FloatArray, at: int) -> FloatArray:
    return g[at : at + 16].reshape(4, 4)


@numba.njit(**KERNEL, inline="always")
def ur_joint_1(g: FloatArray, T: FloatArray, ws: FloatArray) -> tuple[bool, float, float]:
    """What every branch of the UR family's solution shares (:func:`_ur_branches`,
    :func:`~seamtrack.control.closed_form_nearest.ik_nearest`): the joint-6 frame ``ws[0]``
    (the torch's placement undone from ``T``) and ``ws[1]`` = P1^-1 of it, and joint 1's two
    solutions psi + k and psi + pi - k; False where the wrist point lies inside the cylinder
    of radius dlat about axis 1 (no solution)."""
    J6 = ws[0]
    mul_into(T, pose_at(g, U_TCP), J6)
    mul_into(pose_at(g, U_P1I), J6, ws[1])
    dlat, s1 = g[U_DLAT], g[U_S1]
    px, py = J6[0, 3], J6[1, 3]
    r = math.hypot(px, py)
    if r <= abs(dlat):
        return False, 0.0, 0.0
    return True, math.atan2(py, px), math.asin(s1 * dlat / r)


@numba.njit(**KERNEL, inline="always")
def ur_q6(
    q5: float, z1x: float, z1y: float, J6: FloatArray, s4: float, q6_near: float
) -> float:  # fmt: skip
    """A UR branch's joint 6 for joint 5 at ``q5`` (``q6_near`` at the wrist singularity)."""
    sn5 = math.sin(q5)
    if abs(sn5) < SINGULAR_SIN:
        return q6_near
    zx = z1x * J6[0, 0] + z1y * J6[1, 0]
    zy = z1x * J6[0, 1] + z1y * J6[1, 1]
    return math.atan2(-zy / (s4 * sn5), zx / (s4 * sn5))


@numba.njit(**KERNEL, inline="always")
def ur_planar(
    ws: FloatArray, P6i: FloatArray, P5i: FloatArray, q5: float, q6: float, a2: float,
    a3: float,
) -> tuple[bool, float, float, float, float]:  # fmt: skip
    """What is left of a UR branch once joints 1, 5 and 6 are known (``ws[2]``: frame 1 to
    joint 6): the planar 3R chain's angle q234 and target (x, y), and joint 3's cosine; False
    where the chain cannot reach."""
    _rz_right(ws[2], -q6, ws[3])
    mul_into(ws[3], P6i, ws[4])
    _rz_right(ws[4], -q5, ws[3])
    A = ws[5]
    mul_into(ws[3], P5i, A)
    x, y = A[0, 3], A[1, 3]
    c3 = (x * x + y * y - a2 * a2 - a3 * a3) / (2.0 * a2 * a3)
    if abs(c3) > 1.0 + 1e-12:
        return False, 0.0, 0.0, 0.0, 0.0
    return True, math.atan2(A[1, 0], A[0, 0]), x, y, min(max(c3, -1.0), 1.0)


@numba.njit(**KERNEL)
def _ur_branches(g: FloatArray, T: FloatArray, q_near: FloatArray, out: FloatArray) -> int:
    """UR family: up to 8 joint solutions of the torch pose ``T`` (metres).

    In the DH frame 1 (after joint 1's link) the joint-6 frame's origin lies ``dlat`` (d2 +
    d3 + d4) along the parallel axes, whatever joints 2 to 6: that gives joint 1. The z row of
    the rotation from frame 1 to joint 6 is (s_a4 s5 c6, -s_a4 s5 s6, -s_a4 s_a5 c5): joints
    5 and 6. What is left, Rz(q2) Tx(a2) Rz(q3) Tx(a3) Rz(q4), is a planar 3R chain."""
    ws = np.empty((6, 4, 4))  # J6, P1i J6, T01^-1 J6, two scratch, A
    reached, psi, k = ur_joint_1(g, T, ws)
    if not reached:
        return 0  # the wrist point inside the cylinder of radius dlat about axis 1
    P2i, P6i, P5i = pose_at(g, U_P2I), pose_at(g, U_P6I), pose_at(g, U_P5I)
    J6 = ws[0]
    a2, a3 = g[U_A2], g[U_A3]
    s1, s4, s5a = g[U_S1], g[U_S4], g[U_S5]
    count = 0
    for q1 in (psi + k, psi + math.pi - k):
        z1x, z1y = s1 * math.sin(q1), -s1 * math.cos(q1)  # frame 1's z in the base
        c5 = -(z1x * J6[0, 2] + z1y * J6[1, 2]) / (s4 * s5a)
        if abs(c5) > 1.0 + 1e-12:
            continue
        c5 = min(max(c5, -1.0), 1.0)
        rz_left_into(-q1, ws[1], ws[3])
        mul_into(P2i, ws[3], ws[2])  # frame 1 to joint 6
        for q5 in (math.acos(c5), -math.acos(c5)):
            q6 = ur_q6(q5, z1x, z1y, J6, s4, q_near[5])
            reached, q234, x, y, c3 = ur_planar(ws, P6i, P5i, q5, q6, a2, a3)
            if not reached:
                continue
            for q3 in (math.acos(c3), -math.acos(c3)):
                q2 = math.atan2(y, x) - math.atan2(a3 * math.sin(q3), a2 + a3 * math.cos(q3))
                row = out[count]
                row[0], row[1], row[2] = q1, q2, q3
                row[3], row[4], row[5] = q234 - q2 - q3, q5, q6
                for j in range(6):
                    row[j] = nearest_turn(row[j], q_near[j])
                count += 1
    return count


# Layout of the spherical-wrist parameters (base frame, zero pose, metres).
W_WT, W_O1, W_U2, W_V, W_HP, W_O2, W_E1, W_E2 = 0, 3, 6, 9, 12, 13, 16, 19
W_O3, W_W0, W_S3, W_U1, W_U3, W_B, W_S6, W_R0 = 22, 24, 26, 27, 30, 33, 42, 43
WRIST_FIELDS = 52


@numba.njit(**KERNEL, inline="always")
def wrist_joint_1(
    g: FloatArray, T: FloatArray, ws: FloatArray
) -> tuple[bool, float, float, FloatArray]:  # fmt: skip
    """What every branch of the spherical wrist's solution shares (:func:`_wrist_branches`,
    :func:`~seamtrack.control.closed_form_nearest.ik_nearest`): joint 1's two solutions
    beta +- k (False: the wrist centre out of reach), the wrist centre from the shoulder's
    origin (d), and ``ws[0]`` = R, ``ws[2]`` = R R0^T B (the wrist's rotation is
    B^T R3^T (R R0^T B) B^T ... in B's basis)."""
    RT = ws[0]
    RT[:, :] = T[:3, :3]
    w = g[W_WT : W_WT + 3]
    c = np.empty(3)
    for i in range(3):
        c[i] = T[i, 3] + RT[i, 0] * w[0] + RT[i, 1] * w[1] + RT[i, 2] * w[2]
    o1, u2, v = g[W_O1 : W_O1 + 3], g[W_U2 : W_U2 + 3], g[W_V : W_V + 3]
    d = c - o1
    a, b = d[0] * u2[0] + d[1] * u2[1] + d[2] * u2[2], d[0] * v[0] + d[1] * v[1] + d[2] * v[2]
    r = math.hypot(a, b)
    hp = g[W_HP]
    if r < abs(hp) or r == 0.0:
        return False, 0.0, 0.0, d
    mul_into(RT, np.ascontiguousarray(g[W_R0 : W_R0 + 9].reshape(3, 3).T), ws[1])
    mul_into(ws[1], g[W_B : W_B + 9].reshape(3, 3), ws[2])
    return True, math.atan2(b, a), math.acos(min(max(hp / r, -1.0), 1.0)), d


@numba.njit(**KERNEL, inline="always")
def wrist_links(g: FloatArray) -> tuple[float, float, float, float]:
    """The spherical wrist arm's planar 2R chain of joints 2 and 3: the link lengths l2, l3
    and their angles g2, g3 in the zero pose."""
    o3x, o3y = g[W_O3], g[W_O3 + 1]
    w0x, w0y = g[W_W0], g[W_W0 + 1]
    l2 = math.hypot(o3x, o3y)
    l3 = math.hypot(w0x - o3x, w0y - o3y)
    return l2, l3, math.atan2(o3y, o3x), math.atan2(w0y - o3y, w0x - o3x)


@numba.njit(**KERNEL, inline="always")
def wrist_plane(
    g: FloatArray, ws: FloatArray, d: FloatArray, q1: float, l2: float, l3: float
) -> tuple[bool, float, float, float]:  # fmt: skip
    """With joint 1 at ``q1``: the wrist centre (``d`` from the shoulder's origin) in the
    plane of joints 2 and 3 (px, py) and the cosine of the elbow's angle (kappa); False where
    the 2R chain cannot reach it (``ws[3]`` overwritten)."""
    o1, o2 = g[W_O1 : W_O1 + 3], g[W_O2 : W_O2 + 3]
    e1, e2 = g[W_E1 : W_E1 + 3], g[W_E2 : W_E2 + 3]
    _rot_into(g[W_U1 : W_U1 + 3], -q1, ws[3])
    P = np.empty(3)
    for i in range(3):
        P[i] = o1[i] - o2[i] + ws[3, i, 0] * d[0] + ws[3, i, 1] * d[1] + ws[3, i, 2] * d[2]
    px = P[0] * e1[0] + P[1] * e1[1] + P[2] * e1[2]
    py = P[0] * e2[0] + P[1] * e2[1] + P[2] * e2[2]
    kappa = (px * px + py * py - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
    if abs(kappa) > 1.0 + 1e-12:
        return False, px, py, kappa
    return True, px, py, min(max(kappa, -1.0), 1.0)


@numba.njit(**KERNEL, inline="always")
def wrist_elbow(g: FloatArray, phi3: float, px: float, py: float) -> tuple[float, float]:
    """Joints 2 and 3 that put the wrist centre at (px, py) in the plane of the 2R chain,
    with the elbow at ``phi3``."""
    o3x, o3y = g[W_O3], g[W_O3 + 1]
    w0x, w0y = g[W_W0], g[W_W0 + 1]
    vx = o3x + math.cos(phi3) * (w0x - o3x) - math.sin(phi3) * (w0y - o3y)
    vy = o3y + math.sin(phi3) * (w0x - o3x) + math.cos(phi3) * (w0y - o3y)
    return math.atan2(py, px) - math.atan2(vy, vx), g[W_S3] * phi3


@numba.njit(**KERNEL, inline="always")
def wrist_rotation(g: FloatArray, ws: FloatArray, q1: float, q2: float, q3: float) -> FloatArray:
    """The rotation a spherical wrist's joints 4-6 are left to make once joints 1-3 are
    known, in the basis (u4, u5, u4 x u5): N = B^T R3^T R R0^T B (``ws[2]``: R R0^T B; ``ws``
    3-6 overwritten, N in ``ws[6]``)."""
    u1, u2, u3 = g[W_U1 : W_U1 + 3], g[W_U2 : W_U2 + 3], g[W_U3 : W_U3 + 3]
    B = g[W_B : W_B + 9].reshape(3, 3)
    _rot_into(u1, q1, ws[3])
    _rot_into(u2, q2, ws[4])
    mul_into(ws[3], ws[4], ws[5])
    _rot_into(u3, q3, ws[3])
    mul_into(ws[5], ws[3], ws[4])  # R3
    _tmul_into(ws[4], ws[2], ws[5])  # R3^T R R0^T B
    _tmul_into(B, ws[5], ws[6])  # N = B^T R3^T R R0^T B
    return ws[6]


@numba.njit(**KERNEL, inline="always")
def wrist_456(N: FloatArray, sb: float, sign: float, q4_near: float) -> tuple[float, float, float]:
    """Joints 4 and 5 and joint 6's angle before its sign (c6) of the wrist rotation ``N`` =
    Rx(q4) Ry(q5) Rx(c6), on the branch ``sign`` (sb = |N[0, 1:]|; ``q4_near`` at the
    singularity, where only q4 - c6 or q4 + c6 is fixed)."""
    q5 = math.atan2(sign * sb, N[0, 0])
    if sb < SINGULAR_SIN:
        q4 = q4_near
        if N[0, 0] > 0.0:
            c6 = math.atan2(N[2, 1], N[1, 1]) - q4
        else:
            c6 = q4 + math.atan2(-N[2, 1], N[1, 1])
    else:
        q4 = math.atan2(sign * N[1, 0], -sign * N[2, 0])
        c6 = math.atan2(sign * N[0, 1], sign * N[0, 2])
    return q4, q5, c6


@numba.njit(**KERNEL)
def _wrist_branches(g: FloatArray, T: FloatArray, q_near: FloatArray, out: FloatArray) -> int:
    """Spherical wrist: up to 8 joint solutions of the torch pose ``T`` (metres).

    Product of exponentials about the zero pose's axes: the wrist centre c = p + R w_tcp moves
    with joints 1-3 only. Joint 1 turns axis 2 so that c lies in the plane of the arm
    (``a cos q1 + b sin q1 = h``), joints 2 and 3 are a planar 2R chain to it, and the wrist
    rotation left, in the basis (u4, u5, u4 x u5), is Rx(q4) Ry(q5) Rx(+-q6)."""
    ws = np.empty((7, 3, 3))  # R, its R0^T B, rotations, products
    reached, beta, k, d = wrist_joint_1(g, T, ws)
    if not reached:
        return 0
    l2, l3, g2, g3 = wrist_links(g)
    s6 = g[W_S6]
    count = 0
    for q1 in (beta + k, beta - k):
        inside, px, py, kappa = wrist_plane(g, ws, d, q1, l2, l3)
        if not inside:
            continue
        for phi3 in (g2 - g3 + math.acos(kappa), g2 - g3 - math.acos(kappa)):
            q2, q3 = wrist_elbow(g, phi3, px, py)
            N = wrist_rotation(g, ws, q1, q2, q3)
            sb = math.hypot(N[0, 1], N[0, 2])
            for sign in (1.0, -1.0):
                q4, q5, c6 = wrist_456(N, sb, sign, q_near[3])
                row = out[count]
                row[0], row[1], row[2] = q1, q2, q3
                row[3], row[4], row[5] = q4, q5, s6 * c6
                for j in range(6):
                    row[j] = nearest_turn(row[j], q_near[j])
                count += 1
    return count


@numba.njit(**KERNEL)
def ik_branches(
    kind: int, g: FloatArray, T: FloatArray, q_near: FloatArray, out: FloatArray
) -> int:
    """The closed-form joint solutions (rows of ``out``, (8, 6)) of the torch pose ``T``
    (4 x 4, metres, base frame), each joint turned by whole turns to the nearest of
    ``q_near``; returns how many (0: none, or no closed form)."""
    if kind == KIND_UR:
        return _ur_branches(g, T, q_near, out)
    if kind == KIND_WRIST:
        return _wrist_branches(g, T, q_near, out)
    return 0


# ----------------------------------------------------------------- recognising the families
def _is_rx(T: FloatArray) -> bool:
    """A placement Tz(d) Tx(a) Rx(alpha): no y offset, a rotation about x only."""
    R = T[:3, :3]
    off = [R[0, 1], R[0, 2], R[1, 0], R[2, 0], T[1, 3], R[0, 0] - 1.0]
    return bool(np.max(np.abs(off)) <= GEOMETRY_TOL)


def _ur_parameters(place: FloatArray, axes: FloatArray) -> FloatArray | None:
    """The UR family's parameters, or None where the chain is not of that form."""
    if not np.allclose(axes, [0.0, 0.0, 1.0], atol=GEOMETRY_TOL, rtol=0.0):
        return None
    P1 = place[0]
    if not (np.allclose(P1[:3, :3], np.eye(3), atol=GEOMETRY_TOL) and _is_rx(P1)):
        return None
    if abs(P1[0, 3]) > GEOMETRY_TOL or not all(_is_rx(place[k]) for k in range(1, 6)):
        return None
    sin = [float(place[k][2, 1]) for k in range(6)]
    a = [float(place[k][0, 3]) for k in range(6)]
    right = all(abs(abs(sin[k]) - 1.0) <= GEOMETRY_TOL for k in (1, 4, 5))
    parallel = all(abs(sin[k]) <= GEOMETRY_TOL and place[k][1, 1] > 0 for k in (2, 3))
    no_a = all(abs(a[k]) <= GEOMETRY_TOL for k in (1, 4, 5))
    if not (right and parallel and no_a) or min(abs(a[2]), abs(a[3])) <= GEOMETRY_TOL:
        return None
    g = np.zeros(UR_FIELDS)
    for at, M in ((U_P2I, place[1]), (U_P1I, P1), (U_P6I, place[5]), (U_P5I, place[4])):
        g[at : at + 16] = np.linalg.inv(M).ravel()
    g[U_TCP : U_TCP + 16] = np.linalg.inv(place[6]).ravel()
    g[U_A2], g[U_A3] = a[2], a[3]
    g[U_DLAT] = place[2][2, 3] + place[3][2, 3] + place[4][2, 3]
    g[U_S1], g[U_S4], g[U_S5] = sin[1], sin[4], sin[5]
    return g


def _wrist_parameters(frames: FloatArray, axes: FloatArray) -> FloatArray | None:
    """The spherical-wrist parameters from the zero pose's frames, or None where the chain
    is not of that form."""
    u = [frames[k, :3, :3] @ axes[k] for k in range(6)]
    o = [frames[k, :3, 3] for k in range(6)]
    tol = GEOMETRY_TOL
    if abs(u[0] @ u[1]) > tol or np.linalg.norm(np.cross(u[1], u[2])) > tol:
        return None
    if abs(u[3] @ u[4]) > tol or abs(u[4] @ u[5]) > tol:
        return None
    if np.linalg.norm(np.cross(u[3], u[5])) > tol:
        return None
    # The wrist centre: where axis 4 meets axis 5 (perpendicular: the closest point of 4).
    w = o[4] - o[3]
    W0 = o[3] + u[3] * (w @ u[3])
    for k in (3, 4, 5):
        off = W0 - o[k]
        if np.linalg.norm(off - u[k] * (off @ u[k])) > tol:
            return None
    e1, e2 = u[0], np.cross(u[1], u[0])
    o3 = np.array([(o[2] - o[1]) @ e1, (o[2] - o[1]) @ e2])
    w0 = np.array([(W0 - o[1]) @ e1, (W0 - o[1]) @ e2])
    if min(np.linalg.norm(o3), np.linalg.norm(w0 - o3)) <= tol:
        return None
    tcp = frames[6]
    g = np.zeros(WRIST_FIELDS)
    g[W_WT : W_WT + 3] = tcp[:3, :3].T @ (W0 - tcp[:3, 3])
    g[W_O1 : W_O1 + 3], g[W_U2 : W_U2 + 3] = o[0], u[1]
    g[W_V : W_V + 3] = np.cross(u[0], u[1])
    g[W_HP] = (W0 - o[0]) @ u[1]
    g[W_O2 : W_O2 + 3], g[W_E1 : W_E1 + 3], g[W_E2 : W_E2 + 3] = o[1], e1, e2
    g[W_O3 : W_O3 + 2], g[W_W0 : W_W0 + 2] = o3, w0
    g[W_S3] = 1.0 if u[2] @ u[1] > 0 else -1.0
    g[W_U1 : W_U1 + 3], g[W_U3 : W_U3 + 3] = u[0], u[2]
    g[W_B : W_B + 9] = np.column_stack([u[3], u[4], np.cross(u[3], u[4])]).ravel()
    g[W_S6] = 1.0 if u[5] @ u[3] > 0 else -1.0
    g[W_R0 : W_R0 + 9] = tcp[:3, :3].ravel()
    return g


def closed_form_of(chain: tuple[Any, ...], lower: FloatArray, upper: FloatArray,
                   fk: Any) -> tuple[int, FloatArray]:  # fmt: skip
    """The closed-form solver of a chain (``place``, ``axes``, ``kinds``, ``index``, as
    :class:`~seamtrack.control.kinematics.ArmKinematics` holds it), proven on seeded random
    poses (``fk(q)``: the torch pose in metres), or (:data:`KIND_NONE`, empty) where the arm
    has none that passes."""
    place, axes, kinds, index = chain
    none = (KIND_NONE, np.zeros(0))
    if len(axes) != 6 or len(lower) != 6 or (kinds != 0).any() or (index != np.arange(6)).any():
        return none
    zero = np.zeros(6)
    frames = fk(zero, frames=True)
    for kind, g in ((KIND_UR, _ur_parameters(place, axes)),
                    (KIND_WRIST, _wrist_parameters(frames, axes))):  # fmt: skip
        if g is not None and _proven(kind, g, lower, upper, fk):
            return kind, g
    return none


def _proven(kind: int, g: FloatArray, lower: FloatArray, upper: FloatArray, fk: Any) -> bool:
    """Every branch of seeded random poses back on the pose (1e-12 m, 1e-9 rad), and the
    drawn joints among them."""
    rng = np.random.default_rng(2026)
    lo, hi = np.maximum(lower, -math.pi), np.minimum(upper, math.pi)
    out = np.empty((8, 6))
    for _ in range(24):
        q = rng.uniform(lo, hi)
        T = fk(q)
        count = ik_branches(kind, g, T, q, out)
        if count == 0:
            return False
        found = False
        for row in out[:count]:
            T2 = fk(row)
            if np.linalg.norm(T2[:3, 3] - T[:3, 3]) > 1e-12:
                return False
            if np.abs(T2[:3, :3] - T[:3, :3]).max() > 1e-9:
                return False
            found = found or bool(np.abs(row - q).max() < 1e-7)
        if not found:
            return False
    return True
