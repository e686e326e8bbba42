"""Compiled kinematics of a serial arm and its whole control tick (numba).

The arm's control tick (:meth:`seamtrack.control.arm.ArticulatedRobot.step`) runs here in one
compiled call, as the gantry's does (:mod:`seamtrack.simulation.ticks`): the Cartesian
interpolator (:func:`seamtrack.control.robot.axes_step`), the orientation set-point, the inverse
kinematics, the joint limits, the servo (:func:`seamtrack.control.servo.loops_step`) and the
forward kinematics of the measured joints.

Kinematics work on the chain that :class:`~seamtrack.control.kinematics.ArmKinematics` reads
from the URDF through Pinocchio (metres): each joint's fixed placement, its axis and kind, and
the torch tip's placement on the last joint (``chain_fk``, held to Pinocchio's by the tests).
The inverse kinematics is closed-form where the arm has one
(:mod:`seamtrack.control.closed_form`: the UR family, spherical-wrist 6R arms), the branch
nearest the last joint set-point; otherwise, or where the pose has no closed-form solution,
damped least-squares Newton steps from the last set-point (at 1 kHz the pose moves microns per
tick, so one step leaves a residual of the order of the error squared).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.control.closed_form import KIND_NONE, mul, mul_into, rodrigues_into
from seamtrack.control.closed_form_nearest import ik_nearest_in
from seamtrack.control.robot import axes_step
from seamtrack.control.servo import loops_step
from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Joint kinds in a chain.
REVOLUTE, PRISMATIC = 0, 1

#: Damping (m, rad) of the per-tick Newton step (where no closed form applies).
TICK_DAMPING = 1e-3

#: A tick's pose error (m, rad) below which one Newton step is enough: its residual is of the
#: order of the error squared, plus the damping's share (TICK_DAMPING / sigma_min)^2 of it,
#: below 1e-5 mm; a larger error (a limit acted, or the start) gets up to two more steps.
ONE_STEP_ERROR = 1e-4

#: Rows of the tick's parameter array ``par``.
P_DT, P_W_MAX, P_DW_MAX, P_GAIN, P_SOLVER, P_A_MAX = 0, 1, 2, 3, 4, 5
PAR_FIELDS = 6
#: Rows of the joint table ``jl``: lower, upper, 1 / velocity limit, 1 / (acceleration * dt).
J_LO, J_HI, J_INV_V, J_INV_A = 0, 1, 2, 3
#: Rows of the joint state ``jnt``: set-point q, its velocity, measured joints, servo q, v,
#: held set-point.
S_REF, S_QD, S_JOINTS, S_SQ, S_SV, S_HELD = 0, 1, 2, 3, 4, 5
#: Rows of ``cart``: position set-point q, v (mm, base), measured torch tip q, v.
C_SQ, C_SV, C_Q, C_V = 0, 1, 2, 3
#: Fields of the command ``cmd``: has target, target (3), speed, feed-forward (3), stop,
#: has rotation, new goal, has angular feed-forward, angular feed-forward (3), rotation (9).
M_HAS, M_T, M_SPEED, M_FF, M_STOP = 0, 1, 4, 5, 8
M_HAS_ROT, M_NEW_GOAL, M_HAS_W, M_W, M_ROT = 9, 10, 11, 12, 15
CMD_FIELDS = 24
#: Counters ``cnt``: ticks a limit acted on, ticks clamped, servo tick, ipo ticks (-1: none).
K_LIMITED, K_CLAMPED, K_SERVO_TICK, K_IPO = 0, 1, 2, 3


#: The tick's scratch (:func:`work_size`): offsets of a 3 x 3, a 3 x 3 product, a rotation
#: vector, the position set-point (m), a 4 x 4 pose, the closed form's 6 x 4 x 4; then three
#: joint vectors and the chain's frames.
W_TMP, W_PROD, W_LOG, W_P, W_T, W_IK, W_JOINTS = 0, 9, 18, 21, 24, 40, 136


def work_size(dof: int) -> int:
    """Floats of :func:`arm_step`'s scratch for an arm of ``dof`` joints (the chain has at
    most as many)."""
    return W_JOINTS + 3 * dof + 16 * (dof + 1)


class ArmModel(NamedTuple):
    """What an arm's control tick reads and never changes (Pinocchio's *model*): the tick's
    parameters (rows ``P_*``), the Cartesian interpolator's limits
    (:attr:`CartesianRobot._limits <seamtrack.control.robot.CartesianRobot>`), the joint table
    (rows ``J_*``), the servo's table, the closed form's geometry
    (:mod:`seamtrack.control.closed_form`) and the chain (:attr:`ArmKinematics.chain
    <seamtrack.control.kinematics.ArmKinematics.chain>`: each joint's placement, axis, kind and
    index)."""

    par: FloatArray
    limits: FloatArray
    joint_limits: FloatArray
    servo: FloatArray
    geometry: FloatArray
    place: FloatArray
    axes: FloatArray
    kinds: IntArray
    joint_index: IntArray


class ArmData(NamedTuple):
    """What an arm's control tick updates in place (Pinocchio's *data*): the Cartesian
    set-point and the measured torch tip (``cart``, rows ``C_*``), the orientation set-point,
    its goal and the measured rotation (``rot``, (3, 3, 3)), the set-point's angular velocity
    (``omega``), the joints (``jnt``, rows ``S_*``), the counters (``cnt``, ``K_*``), the
    command (``cmd``, fields ``M_*``) and the tick's scratch (``work``, :func:`work_size`), so
    that a tick allocates nothing."""

    cart: FloatArray
    rot: FloatArray
    omega: FloatArray
    jnt: FloatArray
    cnt: IntArray
    cmd: FloatArray
    work: FloatArray


@numba.njit(**KERNEL)
def rotation_about(axis: FloatArray, angle: float, out: FloatArray) -> None:
    """``out`` (3, 3) = rotation by ``angle`` about the unit ``axis`` (Rodrigues)."""
    rodrigues_into(axis[0], axis[1], axis[2], angle, out)


@numba.njit(**KERNEL)
def exp3(w: FloatArray) -> FloatArray:
    """(3, 3) rotation of the rotation vector ``w`` (rad)."""
    angle = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    out = np.eye(3)
    if angle < 1e-300:
        return out
    rotation_about(w / angle, angle, out)
    return out


@numba.njit(**KERNEL)
def _turn(wx: float, wy: float, wz: float, R: FloatArray, tmp: FloatArray) -> None:
    """R = exp3(w) @ R in place (``tmp``: a 3 x 3 scratch)."""
    angle = math.sqrt(wx * wx + wy * wy + wz * wz)
    if angle < 1e-300:
        return
    rodrigues_into(wx / angle, wy / angle, wz / angle, angle, tmp)
    for j in range(3):
        a, b, c = R[0, j], R[1, j], R[2, j]
        for i in range(3):
            R[i, j] = tmp[i, 0] * a + tmp[i, 1] * b + tmp[i, 2] * c


@numba.njit(**KERNEL)
def mul_t(A: FloatArray, B: FloatArray) -> FloatArray:
    """A @ B.T for 3 x 3 matrices."""
    out = np.empty((3, 3))
    _mul_t_into(A, B, out)
    return out


@numba.njit(**KERNEL, inline="always")
def _mul_t_into(A: FloatArray, B: FloatArray, out: FloatArray) -> None:
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[j, 0] + A[i, 1] * B[j, 1] + A[i, 2] * B[j, 2]


@numba.njit(**KERNEL)
def _log3_into(R: FloatArray, out: FloatArray) -> None:
    """``out`` = :func:`log3` of R (its arithmetic; near pi, its call)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    c = min(max(0.5 * (tr - 1.0), -1.0), 1.0)
    v0, v1, v2 = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    angle = math.acos(c)
    if angle < 1e-4:
        k = 1.0 + angle * angle / 6.0
        out[0], out[1], out[2] = 0.5 * v0 * k, 0.5 * v1 * k, 0.5 * v2 * k
    elif angle < math.pi - 1e-4:
        k = 0.5 * angle / math.sin(angle)
        out[0], out[1], out[2] = v0 * k, v1 * k, v2 * k
    else:
        out[:] = log3(R)


@numba.njit(**KERNEL)
def log3(R: FloatArray) -> FloatArray:
    """(3,) rotation vector (axis times angle, rad) of a rotation matrix, accurate near 0 and
    near pi (Pinocchio's ``log3`` to rounding)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    c = min(max(0.5 * (tr - 1.0), -1.0), 1.0)
    v = np.empty(3)
    v[0], v[1], v[2] = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    angle = math.acos(c)
    if angle < 1e-4:  # sin(angle) / angle by its series: 1 - angle^2 / 6
        return 0.5 * v * (1.0 + angle * angle / 6.0)
    if angle < math.pi - 1e-4:
        return v * (0.5 * angle / math.sin(angle))
    # Near pi: the axis from the diagonal, its sign from the skew part.
    out = np.empty(3)
    for i in range(3):
        out[i] = math.sqrt(max((R[i, i] - c) / (1.0 - c), 0.0))
    k = 0
    for i in range(3):
        if out[i] > out[k]:
            k = i
    for i in range(3):
        if i != k:
            out[i] = (R[i, k] + R[k, i]) / (2.0 * (1.0 - c) * out[k])
    if v[k] < 0.0:
        out *= -1.0
    norm = math.sqrt(out[0] ** 2 + out[1] ** 2 + out[2] ** 2)
    return out * (angle / norm)


@numba.njit(**KERNEL)
def chain_fk(
    q: FloatArray, place: FloatArray, axes: FloatArray, kinds: IntArray, index: IntArray,
    frames: FloatArray,
) -> None:  # fmt: skip
    """Joint frames and the torch tip of a chain (metres): ``frames[k]`` the frame of chain
    joint k (after its motion), ``frames[m]`` the torch tip (``place[m]`` on the last joint).
    ``index[k]``: which entry of ``q`` moves chain joint k."""
    m = axes.shape[0]
    for k in range(m):
        F = frames[k]
        if k == 0:
            F[:, :] = place[0]
        else:
            mul_into(frames[k - 1], place[k], F)
        x = q[index[k]]
        ax, ay, az = axes[k, 0], axes[k, 1], axes[k, 2]
        if kinds[k] == REVOLUTE:
            c, s = math.cos(x), math.sin(x)
            t = 1.0 - c
            r00, r01, r02 = c + t * ax * ax, t * ax * ay - s * az, t * ax * az + s * ay
            r10, r11, r12 = t * ax * ay + s * az, c + t * ay * ay, t * ay * az - s * ax
            r20, r21, r22 = t * ax * az - s * ay, t * ay * az + s * ax, c + t * az * az
            for i in range(3):
                f0, f1, f2 = F[i, 0], F[i, 1], F[i, 2]
                F[i, 0] = f0 * r00 + f1 * r10 + f2 * r20
                F[i, 1] = f0 * r01 + f1 * r11 + f2 * r21
                F[i, 2] = f0 * r02 + f1 * r12 + f2 * r22
        else:
            for i in range(3):
                F[i, 3] += x * (F[i, 0] * ax + F[i, 1] * ay + F[i, 2] * az)
    mul_into(frames[m - 1], place[m], frames[m])


@numba.njit(**KERNEL)
def chain_jacobian(
    q: FloatArray, place: FloatArray, axes: FloatArray, kinds: IntArray, index: IntArray,
    frames: FloatArray, J: FloatArray,
) -> None:  # fmt: skip
    """``chain_fk`` and the torch tip's Jacobian ``J`` (6, n): linear rows (m/s per rad/s),
    then angular, base axes (Pinocchio's ``LOCAL_WORLD_ALIGNED``); joints off the chain have
    zero columns."""
    chain_fk(q, place, axes, kinds, index, frames)
    m = axes.shape[0]
    J[:, :] = 0.0
    p = frames[m, :3, 3]
    for k in range(m):
        F = frames[k]
        a = axes[k]
        w = np.empty(3)
        for i in range(3):
            w[i] = F[i, 0] * a[0] + F[i, 1] * a[1] + F[i, 2] * a[2]
        j = index[k]
        if kinds[k] == REVOLUTE:
            r = p - frames[k, :3, 3]
            J[0, j] = w[1] * r[2] - w[2] * r[1]
            J[1, j] = w[2] * r[0] - w[0] * r[2]
            J[2, j] = w[0] * r[1] - w[1] * r[0]
            J[3, j], J[4, j], J[5, j] = w[0], w[1], w[2]
        else:
            J[0, j], J[1, j], J[2, j] = w[0], w[1], w[2]


@numba.njit(**KERNEL)
def spd_solve(A: FloatArray, b: FloatArray) -> FloatArray:
    """x with A x = b for a symmetric positive definite A (Cholesky); NaN where it is not."""
    n = A.shape[0]
    L = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if not s > 0.0:
                    return np.full(n, np.nan)
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    y = np.empty(n)
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    x = np.empty(n)
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s -= L[k, i] * x[k]
        x[i] = s / L[i, i]
    return x


@numba.njit(**KERNEL)
def newton_ik(
    p_set: FloatArray, R_set: FloatArray, q0: FloatArray, place: FloatArray, axes: FloatArray,
    kinds: IntArray, index: IntArray, steps: int,
) -> FloatArray:  # fmt: skip
    """Up to ``steps`` damped least-squares Newton steps from ``q0`` towards the torch pose
    (``p_set`` in metres), stopping after the first whose error was below
    :data:`ONE_STEP_ERROR` (``(J J^T + lambda^2 I) y = e``, ``dq = J^T y``)."""
    m = axes.shape[0]
    frames = np.empty((m + 1, 4, 4))
    J = np.empty((6, q0.shape[0]))
    q = q0.copy()
    e = np.empty(6)
    damp2 = TICK_DAMPING * TICK_DAMPING
    for _ in range(steps):
        chain_jacobian(q, place, axes, kinds, index, frames, J)
        T = frames[m]
        worst = 0.0
        for i in range(3):
            e[i] = p_set[i] - T[i, 3]
        e[3:] = log3(mul_t(R_set, T[:3, :3]))
        for i in range(6):
            worst = max(worst, abs(e[i]))
        A = mul(J, np.ascontiguousarray(J.T))
        for i in range(6):
            A[i, i] += damp2
        q += mul(np.ascontiguousarray(J.T), spd_solve(A, e).reshape(6, 1))[:, 0]
        if worst < ONE_STEP_ERROR:
            break
    return q


@numba.njit(**KERNEL)
def solve_pose(
    p_set: FloatArray, R_set: FloatArray, q_near: FloatArray, solver: int, geo: FloatArray,
    place: FloatArray, axes: FloatArray, kinds: IntArray, index: IntArray, out: FloatArray,
    T: FloatArray, ws: FloatArray,
) -> None:  # fmt: skip
    """Joint positions at the torch pose (``p_set`` in metres) into ``out``: the closed-form
    branch nearest ``q_near`` where the arm has a closed form and the pose a solution, else
    Newton steps from ``q_near`` (``T``: a 4 x 4 scratch, ``ws``: the closed form's)."""
    if solver != KIND_NONE:
        T[:, :] = 0.0
        T[3, 3] = 1.0
        T[:3, :3] = R_set
        T[:3, 3] = p_set
        if ik_nearest_in(solver, geo, T, q_near, out, ws):  # nearest_branch of ik_branches
            return
    out[:] = newton_ik(p_set, R_set, q_near, place, axes, kinds, index, 3)


@numba.njit(**KERNEL)
def arm_step(model: ArmModel, data: ArmData) -> None:
    """One control tick of an arm (``data`` updated in place): the interpolator, the
    orientation set-point, the inverse kinematics, the joint limits, the servo and the forward
    kinematics of the measured joints."""
    cart, cmd, work, jnt = data.cart, data.cmd, data.work, data.jnt
    dt = model.par[P_DT]
    has = cmd[M_HAS] > 0.0
    axes_step(
        cart[C_SQ], cart[C_SV], model.limits, dt, has, cmd[M_T], cmd[M_T + 1], cmd[M_T + 2],
        cmd[M_SPEED], cmd[M_FF], cmd[M_FF + 1], cmd[M_FF + 2], cmd[M_STOP] > 0.0,
    )  # fmt: skip
    _orientation_step(model.par, data, has)
    # Inverse kinematics from the last joint set-point.
    p_set = work[W_P : W_P + 3]
    for i in range(3):
        p_set[i] = cart[C_SQ, i] * 1e-3
    q_ref = jnt[S_REF]
    n = q_ref.shape[0]
    q = work[W_JOINTS : W_JOINTS + n]
    solve_pose(
        p_set, data.rot[0], q_ref, int(model.par[P_SOLVER]), model.geometry, model.place,
        model.axes, model.kinds, model.joint_index, q, work[W_T : W_T + 16].reshape(4, 4),
        work[W_IK : W_IK + 96].reshape(6, 4, 4),
    )  # fmt: skip
    new_ref = _joint_limits(model.joint_limits, data, q, dt)
    _servo_and_measure(model, data, new_ref, dt)


@numba.njit(**KERNEL, inline="always")
def _goal_velocity(par: FloatArray, data: ArmData) -> tuple[float, float, float]:
    """The orientation set-point's commanded angular velocity: towards the goal (a new goal
    from the command, or the goal turned by the command's feed-forward), proportional to the
    error, capped by the speed from which braking at the angular acceleration limit stops on
    the goal (no overshoot), plus the goal's own turning, capped at the angular speed limit."""
    cmd, work = data.cmd, data.work
    R_set, R_goal = data.rot[0], data.rot[1]
    dt = par[P_DT]
    wx = wy = wz = 0.0
    fx, fy, fz = cmd[M_W], cmd[M_W + 1], cmd[M_W + 2]
    if cmd[M_NEW_GOAL] > 0.0:
        R_goal[:, :] = cmd[M_ROT : M_ROT + 9].reshape(3, 3)
        cmd[M_NEW_GOAL] = 0.0
    elif cmd[M_HAS_W] > 0.0:
        _turn(fx * dt, fy * dt, fz * dt, R_goal, work[W_TMP : W_TMP + 9].reshape(3, 3))
    prod, err = work[W_PROD : W_PROD + 9].reshape(3, 3), work[W_LOG : W_LOG + 3]
    _mul_t_into(R_goal, R_set, prod)
    _log3_into(prod, err)
    size = math.sqrt(err[0] ** 2 + err[1] ** 2 + err[2] ** 2)
    speed = min(par[P_GAIN] * size, math.sqrt(2.0 * par[P_A_MAX] * size))
    if size > 0.0:
        k = speed / size
        wx, wy, wz = err[0] * k, err[1] * k, err[2] * k
    if cmd[M_HAS_W] > 0.0:
        wx, wy, wz = wx + fx, wy + fy, wz + fz
    norm = math.sqrt(wx * wx + wy * wy + wz * wz)
    if norm > par[P_W_MAX]:
        k = par[P_W_MAX] / norm
        wx, wy, wz = wx * k, wy * k, wz * k
    return wx, wy, wz


@numba.njit(**KERNEL, inline="always")
def _orientation_step(par: FloatArray, data: ArmData, has: bool) -> None:
    """The orientation set-point's tick: its angular velocity towards the commanded one
    (:func:`_goal_velocity`; zero without a command), within the angular acceleration limit,
    and the set-point turned by it."""
    omega = data.omega
    wx = wy = wz = 0.0
    if has and data.cmd[M_HAS_ROT] > 0.0:
        wx, wy, wz = _goal_velocity(par, data)
    dx, dy, dz = wx - omega[0], wy - omega[1], wz - omega[2]
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    if norm > par[P_DW_MAX]:
        k = par[P_DW_MAX] / norm
        dx, dy, dz = dx * k, dy * k, dz * k
    omega[0] += dx
    omega[1] += dy
    omega[2] += dz
    if omega[0] != 0.0 or omega[1] != 0.0 or omega[2] != 0.0:
        dt = par[P_DT]
        tmp = data.work[W_TMP : W_TMP + 9].reshape(3, 3)
        _turn(omega[0] * dt, omega[1] * dt, omega[2] * dt, data.rot[0], tmp)


@numba.njit(**KERNEL, inline="always")
def _joint_limits(jl: FloatArray, data: ArmData, q: FloatArray, dt: float) -> FloatArray:
    """The joint set-point moved towards the inverse kinematics' joints ``q`` within the
    joints' velocity and acceleration limits (all joints scaled together, so the tool keeps
    its path) and their travel (clamped); the counters of limited and clamped ticks. Returns
    the new set-point (in the tick's scratch)."""
    jnt, cnt, work = data.jnt, data.cnt, data.work
    q_ref = jnt[S_REF]
    n = q_ref.shape[0]
    qd = work[W_JOINTS + n : W_JOINTS + 2 * n]
    new_ref = work[W_JOINTS + 2 * n : W_JOINTS + 3 * n]
    for j in range(n):
        qd[j] = (q[j] - q_ref[j]) / dt
    limited = False
    over = 0.0
    for j in range(n):
        over = max(over, abs(qd[j]) * jl[J_INV_V, j])
    if over > 1.0:
        for j in range(n):
            qd[j] /= over
        limited = True
    over = 0.0
    for j in range(n):
        over = max(over, abs(qd[j] - jnt[S_QD, j]) * jl[J_INV_A, j])
    if over > 1.0:
        for j in range(n):
            qd[j] = jnt[S_QD, j] + (qd[j] - jnt[S_QD, j]) / over
        limited = True
    for j in range(n):
        new_ref[j] = q_ref[j] + qd[j] * dt
    out = False
    for j in range(n):
        if new_ref[j] < jl[J_LO, j] or new_ref[j] > jl[J_HI, j]:
            out = True
    if out:
        for j in range(n):
            new_ref[j] = min(max(new_ref[j], jl[J_LO, j]), jl[J_HI, j])
        cnt[K_CLAMPED] += 1
        for j in range(n):
            qd[j] = (new_ref[j] - q_ref[j]) / dt
    if limited:
        cnt[K_LIMITED] += 1
    jnt[S_REF] = new_ref
    jnt[S_QD] = qd
    return new_ref


@numba.njit(**KERNEL, inline="always")
def _servo_and_measure(model: ArmModel, data: ArmData, new_ref: FloatArray, dt: float) -> None:
    """The joint servo on the new set-point (held for the interpolation's ticks), then the
    measured joints' forward kinematics: the torch tip's position and velocity (mm) and
    rotation."""
    jnt, cnt, cart, jl = data.jnt, data.cnt, data.cart, model.joint_limits
    n = new_ref.shape[0]
    if cnt[K_IPO] > 0:
        if cnt[K_SERVO_TICK] % cnt[K_IPO] == 0:
            jnt[S_HELD] = new_ref
        cnt[K_SERVO_TICK] += 1
        loops_step(jnt[S_SQ], jnt[S_SV], jnt[S_HELD], model.servo, dt)
        for j in range(n):
            jnt[S_JOINTS, j] = min(max(jnt[S_SQ, j], jl[J_LO, j]), jl[J_HI, j])
    else:
        jnt[S_JOINTS] = new_ref
    m = model.axes.shape[0]
    start = W_JOINTS + 3 * n
    frames = data.work[start : start + 16 * (m + 1)].reshape(m + 1, 4, 4)
    chain_fk(jnt[S_JOINTS], model.place, model.axes, model.kinds, model.joint_index, frames)
    T = frames[m]
    for i in range(3):
        x = T[i, 3] * 1e3
        cart[C_V, i] = (x - cart[C_Q, i]) / dt
        cart[C_Q, i] = x
    data.rot[2] = T[:3, :3]


@numba.njit(**KERNEL)
def chain_figures(
    joints: FloatArray, place: FloatArray, axes: FloatArray, kinds: IntArray, index: IntArray,
    a: int, b: int, wrist: FloatArray, jacobians: FloatArray,
) -> None:  # fmt: skip
    """For each row of ``joints``: the angle (rad, 0..pi/2) between the axes of chain joints
    ``a`` and ``b`` (the wrist's 4 and 6) and the torch tip's Jacobian."""
    m = axes.shape[0]
    frames = np.empty((m + 1, 4, 4))
    for r in range(joints.shape[0]):
        chain_jacobian(joints[r], place, axes, kinds, index, frames, jacobians[r])
        c = 0.0
        for i in range(3):
            wa = frames[a, i, 0] * axes[a, 0] + frames[a, i, 1] * axes[a, 1]
            wa += frames[a, i, 2] * axes[a, 2]
            wb = frames[b, i, 0] * axes[b, 0] + frames[b, i, 1] * axes[b, 1]
            wb += frames[b, i, 2] * axes[b, 2]
            c += wa * wb
        wrist[r] = math.acos(min(abs(c), 1.0))
