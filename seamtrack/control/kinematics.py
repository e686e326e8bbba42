"""Articulated-arm kinematics on Pinocchio: a frozen model, a mutable data (STYLE.md).

Pinocchio (the ``pin`` package) reads the URDF, and computes forward kinematics and frame
Jacobians in compiled code (about 1 us each for a 6-axis arm); seamtrack adds the tool
(``T_flange_tcp``), millimetres, and a damped least-squares inverse kinematics. Pinocchio
speaks metres: positions are converted at this module's boundary and nowhere else.

The chain Pinocchio reads (:attr:`ArmKinematics.chain`) also feeds the compiled control tick
(:mod:`seamtrack.control.arm_kernels`) and, where the arm has one, the closed-form inverse
kinematics (:mod:`seamtrack.control.closed_form`: the UR family, spherical-wrist arms;
:meth:`ArmKinematics.ik_branches`), recognised from the URDF and proven on seeded poses when
the arm is built.

Named arms (:data:`ARM_MODELS`) are URDF files written from the makers' published
Denavit-Hartenberg tables, dimensions and axis data (each number is cited in its file under
``seamtrack/control/arms/``); ``robot.urdf`` loads any other serial arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.control.closed_form import KIND_NAMES, KIND_NONE, closed_form_of, ik_branches
from seamtrack.control.urdf import check_urdf, quiet_c_stderr, read_urdf
from seamtrack.errors import SceneError

FloatArray = NDArray[np.float64]

#: Metres per millimetre (Pinocchio's unit against ours).
M_PER_MM = 1e-3

#: IK convergence: position (mm) and orientation (rad) error below which a pose is reached.
IK_TOL_MM = 1e-10
IK_TOL_RAD = 1e-12

_EYE6 = np.eye(6)


@dataclass(frozen=True)
class ArmModel:
    """What a named arm is: its URDF and what a URDF cannot say.

    Attributes
    ----------
    name : str
    urdf : str
        File name under ``seamtrack/control/arms/``.
    acceleration_max_rad_s2 : tuple of float
        Joint acceleration limits (a URDF has none; see ``source``).
    home_deg : tuple of float
        The configuration the inverse kinematics starts from (elbow up, wrist bent).
    source : str
        Where the numbers come from.
    """

    name: str
    urdf: str
    acceleration_max_rad_s2: tuple[float, ...]
    home_deg: tuple[float, ...]
    source: str


#: The arms ``robot.model`` names. Joint accelerations are not in either maker's data sheet:
#: we take URScript's default joint acceleration of ``movej`` (a = 1.4 rad/s^2, Universal Robots,
#: "The URScript Programming Language") for both, a cautious value for welding speeds.
ARM_MODELS: dict[str, ArmModel] = {
    "ur10e": ArmModel(
        name="ur10e",
        urdf="ur10e.urdf",
        acceleration_max_rad_s2=(1.4,) * 6,
        home_deg=(0.0, -90.0, 90.0, -90.0, -90.0, 0.0),
        source="Universal Robots: DH parameters (support article 45257), UR10e data sheet",
    ),
    "kr16": ArmModel(
        name="kr16",
        urdf="kr16.urdf",
        acceleration_max_rad_s2=(1.4,) * 6,
        home_deg=(0.0, -90.0, 90.0, 0.0, 45.0, 0.0),
        source="KUKA: Specification KR 16-2 (principal dimensions, axis data)",
    ),
}


def import_pinocchio() -> Any:
    try:
        import pinocchio
    except ImportError:  # pragma: no cover - the extra is part of dev and CI
        raise SceneError(
            "articulated arms need Pinocchio, which is not installed",
            field="robot.model",
            fix="pip install 'seamtrack[arms]' (the pin package), or use robot.model = "
            '"cartesian"',
        ) from None
    return pinocchio


@dataclass(frozen=True, eq=False)
class IKResult:
    """An inverse-kinematics answer; falsy when the pose was not reached.

    Attributes
    ----------
    q : (n,) float
        Joint positions (rad), the last iterate when not converged.
    error_mm, error_rad : float
        Remaining position and orientation error.
    iterations : int
    """

    q: FloatArray
    error_mm: float
    error_rad: float
    iterations: int

    def __bool__(self) -> bool:
        return self.error_mm <= 1e-6 and self.error_rad <= 1e-9


@dataclass(frozen=True, eq=False)
class ArmKinematics:
    """A serial arm's kinematics with a tool: the frozen description.

    Build it with :meth:`named` or :meth:`from_urdf`. Per-call state lives in a Pinocchio
    ``data`` (:meth:`new_data`), which the caller owns.

    Attributes
    ----------
    name : str
    model : pinocchio.Model
        The kinematic tree and limits (metres, radians). Never modified.
    frame_id : int
        Pinocchio frame of the flange (the last frame of the tree unless one is named
        ``flange`` or ``tool0``).
    T_flange_tcp : (4, 4) float
        The torch tip on the flange, mm.
    lower_rad, upper_rad, velocity_max_rad_s, acceleration_max_rad_s2 : (n,) float
        Joint limits.
    home_rad : (n,) float
        Start configuration of the inverse kinematics.
    chain : tuple of arrays
        The joints from the base to the torch tip, as the compiled kinematics
        (:mod:`seamtrack.control.arm_kernels`) take them: each joint's fixed placement
        (metres) and, last, the torch tip's on the last joint, (m + 1, 4, 4); the joints'
        axes (m, 3) and kinds (m,: 0 revolute, 1 prismatic); which joint position moves each.
    solver : int
        The inverse kinematics' closed form (:mod:`seamtrack.control.closed_form`:
        ``KIND_UR``, ``KIND_WRIST``) or ``KIND_NONE`` (iterative only); ``geometry`` its
        parameters, read from the URDF.
    """

    name: str
    model: Any
    frame_id: int
    T_flange_tcp: FloatArray
    lower_rad: FloatArray
    upper_rad: FloatArray
    velocity_max_rad_s: FloatArray
    acceleration_max_rad_s2: FloatArray
    home_rad: FloatArray
    tcp_id: int = field(init=False, repr=False)
    chain: tuple[Any, ...] = field(init=False, repr=False)
    solver: int = field(init=False, repr=False)
    geometry: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        pin = import_pinocchio()
        tool = np.array(self.T_flange_tcp, dtype=np.float64)
        object.__setattr__(self, "T_flange_tcp", tool)
        # The torch tip as a frame of the model (on a copy: the caller's model is not touched),
        # so that Pinocchio computes its placement and Jacobian directly.
        model = self.model.copy()
        flange = model.frames[self.frame_id]
        placement = pin.SE3(tool[:3, :3], tool[:3, 3] * M_PER_MM)
        tcp_id = model.addFrame(
            pin.Frame(
                "seamtrack_tcp", flange.parentJoint, self.frame_id,
                flange.placement * placement, pin.FrameType.OP_FRAME,
            )
        )  # fmt: skip
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "tcp_id", int(tcp_id))
        object.__setattr__(self, "chain", _chain(model, int(tcp_id)))
        lower = np.asarray(self.lower_rad, dtype=np.float64)
        upper = np.asarray(self.upper_rad, dtype=np.float64)
        solver, geometry = closed_form_of(self.chain, lower, upper, self.chain_fk)
        object.__setattr__(self, "solver", solver)
        object.__setattr__(self, "geometry", geometry)

    # ----------------------------------------------------------------- construction
    @classmethod
    def named(cls, name: str, T_flange_tcp: ArrayLike | None = None) -> ArmKinematics:
        """One of :data:`ARM_MODELS`."""
        if name not in ARM_MODELS:
            raise SceneError(
                f"unknown robot model {name!r}",
                field="robot.model",
                fix=f'use one of cartesian, {", ".join(ARM_MODELS)}, or robot.urdf = "my_arm.urdf"',
            )
        spec = ARM_MODELS[name]
        text = resources.files("seamtrack.control").joinpath("arms", spec.urdf).read_text()
        return cls._build(
            name,
            text,
            T_flange_tcp,
            np.array(spec.acceleration_max_rad_s2),
            np.radians(spec.home_deg),
            field="robot.model",
        )

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        T_flange_tcp: ArrayLike | None = None,
        acceleration_max_rad_s2: ArrayLike | None = None,
        home_rad: ArrayLike | None = None,
    ) -> ArmKinematics:
        """A serial arm from a URDF file (revolute or prismatic joints, one chain)."""
        path = Path(path)
        text = read_urdf(path, "robot.urdf")
        model = cls._parse(text, "robot.urdf", str(path))
        n = model.nq
        accel = (
            np.full(n, 1.4)
            if acceleration_max_rad_s2 is None
            else np.asarray(acceleration_max_rad_s2, dtype=np.float64)
        )
        home = (
            np.clip(np.zeros(n), model.lowerPositionLimit, model.upperPositionLimit)
            if home_rad is None
            else np.asarray(home_rad, dtype=np.float64)
        )
        return cls._build(path.stem, text, T_flange_tcp, accel, home, field="robot.urdf")

    @staticmethod
    def _parse(text: str, field_name: str, what: str) -> Any:
        pin = import_pinocchio()
        check_urdf(text, what, field_name)  # what urdfdom would print its own errors about
        try:
            with quiet_c_stderr() as printed:
                return pin.buildModelFromXML(text)
        except Exception as exc:  # Pinocchio raises ValueError or RuntimeError
            said = [line.strip() for line in printed if line.strip()]
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise SceneError(
                f"{what} does not parse as a URDF: {first}"
                + (f" (urdfdom: {said[0]})" if said else ""),
                field=field_name,
                fix="check the file's XML (links, joints with parent, child, axis and limits)",
            ) from None

    @classmethod
    def _build(
        cls,
        name: str,
        text: str,
        T_flange_tcp: ArrayLike | None,
        accel: FloatArray,
        home: FloatArray,
        field: str,
    ) -> ArmKinematics:
        model = cls._parse(text, field, name)
        n = model.nq
        if n < 6 or model.nv != n:  # nv: one per joint (nq counts a continuous joint twice)
            raise SceneError(
                f"{name}: a tool needs 6 joints to take any orientation; the URDF has {model.nv}",
                field=field,
                fix="give a 6-axis (or longer) serial arm with revolute or prismatic joints",
            )
        names = [f.name for f in model.frames]
        flange = next((k for k in ("flange", "tool0") if k in names), names[-1])
        lower = np.array(model.lowerPositionLimit, dtype=np.float64)
        upper = np.array(model.upperPositionLimit, dtype=np.float64)
        velocity = np.array(model.velocityLimit, dtype=np.float64)
        if not (np.isfinite(lower).all() and np.isfinite(upper).all() and (lower < upper).all()):
            raise SceneError(
                f"{name}: joint limits must be finite with lower < upper",
                field=field,
                fix="give every joint <limit lower=... upper=... velocity=...>",
            )
        if not (np.isfinite(velocity).all() and (velocity > 0).all()):
            raise SceneError(
                f"{name}: every joint needs a velocity limit > 0",
                field=field,
                fix="set <limit velocity=...> (rad/s) on every joint",
            )
        return cls(
            name=name,
            model=model,
            frame_id=int(model.getFrameId(flange)),
            T_flange_tcp=np.eye(4) if T_flange_tcp is None else np.asarray(T_flange_tcp),
            lower_rad=lower,
            upper_rad=upper,
            velocity_max_rad_s=velocity,
            acceleration_max_rad_s2=np.broadcast_to(accel, (n,)).astype(np.float64),
            home_rad=np.asarray(home, dtype=np.float64),
        )

    # ----------------------------------------------------------------- kinematics
    @property
    def dof(self) -> int:
        return int(self.model.nq)

    def new_data(self) -> Any:
        """A fresh Pinocchio data (the mutable state of every computation)."""
        return self.model.createData()

    def fk(self, q: ArrayLike, data: Any = None) -> FloatArray:
        """``T_base_tcp(q)``, (4, 4), mm."""
        pin = import_pinocchio()
        data = self.new_data() if data is None else data
        pin.forwardKinematics(self.model, data, np.asarray(q, dtype=np.float64))
        pin.updateFramePlacement(self.model, data, self.tcp_id)
        return self._tcp_mm(data)

    def chain_fk(self, q: ArrayLike, frames: bool = False) -> FloatArray:
        """``T_base_tcp(q)`` in **metres** from the compiled chain (Pinocchio's to rounding);
        ``frames``: every joint's frame too, (m + 1, 4, 4), the torch tip last."""
        from seamtrack.control.arm_kernels import chain_fk

        place, axes, kinds, index = self.chain
        out = np.empty((len(axes) + 1, 4, 4))
        chain_fk(np.asarray(q, dtype=np.float64), place, axes, kinds, index, out)
        return out if frames else out[-1]

    @property
    def solver_name(self) -> str:
        """How the inverse kinematics is solved: ``UR closed form``, ``spherical wrist`` or
        ``iterative``."""
        return KIND_NAMES[self.solver]

    def ik_branches(self, T_base_tcp: ArrayLike, q_near: ArrayLike) -> FloatArray:
        """(k, 6) every closed-form joint solution of the torch pose (mm), each joint turned
        by whole turns to the nearest of ``q_near``; (0, n) where the pose has none or the
        arm no closed form (see :attr:`solver`)."""
        T = np.array(T_base_tcp, dtype=np.float64)
        T[:3, 3] *= M_PER_MM
        near = np.asarray(q_near, dtype=np.float64)
        if self.solver == KIND_NONE:
            return np.empty((0, self.dof))
        out = np.empty((8, self.dof))
        count = ik_branches(self.solver, self.geometry, T, near, out)
        return out[:count].copy()

    def _tcp_mm(self, data: Any) -> FloatArray:
        T = data.oMf[self.tcp_id].homogeneous
        T[:3, 3] /= M_PER_MM
        return T

    def jacobian(self, q: ArrayLike, data: Any) -> tuple[FloatArray, FloatArray]:
        """TCP pose and its Jacobian in the base frame.

        Returns
        -------
        T_base_tcp : (4, 4) float
            mm.
        J : (6, n) float
            Rows: TCP linear velocity (m/s per rad/s: Pinocchio's units, so that the damping
            weighs metres against radians), then angular velocity, both in base axes.
        """
        pin = import_pinocchio()
        J = pin.computeFrameJacobian(
            self.model, data, np.asarray(q, dtype=np.float64), self.tcp_id,
            pin.LOCAL_WORLD_ALIGNED,
        )  # fmt: skip
        return self._tcp_mm(data), J

    def tcp_jacobian_m(self, q: FloatArray, data: Any) -> tuple[FloatArray, FloatArray]:
        """TCP pose in metres and its Jacobian (see :meth:`jacobian`), for the control tick:
        one Pinocchio call and one copy, no unit conversion of the pose.

        Returns
        -------
        T_base_tcp : (4, 4) float
            **metres** (a fresh array).
        J : (6, n) float
        """
        pin = import_pinocchio()
        J = pin.computeFrameJacobian(self.model, data, q, self.tcp_id, pin.LOCAL_WORLD_ALIGNED)
        return data.oMf[self.tcp_id].np, J

    def ik(
        self,
        T_base_tcp: ArrayLike,
        q_seed: ArrayLike,
        data: Any = None,
        max_iterations: int = 100,
        damping: float = 1e-3,
    ) -> IKResult:
        """Joint positions that put the TCP at a pose: damped least squares from a seed.

        Each step solves ``(J J^T + lambda^2 I) y = e``, ``dq = J^T y``, with the damping
        ``lambda`` grown near a singularity (where ``J`` loses rank) and shrunk to zero as the
        error vanishes, so that the last steps are Newton steps and converge quadratically.
        Joint limits are not imposed here: callers check them.

        Parameters
        ----------
        T_base_tcp : (4, 4) float
            Target, mm.
        q_seed : (n,) float
        data : pinocchio.Data, optional
        max_iterations : int
        damping : float
            Damping (m or rad) where the error is large.
        """
        pin = import_pinocchio()
        data = self.new_data() if data is None else data
        target = np.asarray(T_base_tcp, dtype=np.float64)
        p_target = target[:3, 3] * M_PER_MM
        R_target = target[:3, :3]
        q = np.array(q_seed, dtype=np.float64)
        err_mm = err_rad = math.inf
        for k in range(max_iterations + 1):
            T, J = self.jacobian(q, data)
            e = np.empty(6)
            e[:3] = p_target - T[:3, 3] * M_PER_MM
            e[3:] = pin.log3(R_target @ T[:3, :3].T)
            err_mm = float(np.linalg.norm(e[:3])) / M_PER_MM
            err_rad = float(np.linalg.norm(e[3:]))
            if (err_mm <= IK_TOL_MM and err_rad <= IK_TOL_RAD) or k == max_iterations:
                return IKResult(q, err_mm, err_rad, k)
            size = float(np.linalg.norm(e))
            lam = min(damping, size)
            step = J.T @ np.linalg.solve(J @ J.T + lam * lam * _EYE6, e)
            # Large steps from a far seed: keep each within a radian so the iteration follows
            # the arm's motion instead of leaping between solution branches.
            longest = float(np.max(np.abs(step)))
            if longest > 0.5:
                step *= 0.5 / longest
            q = q + step
        return IKResult(q, err_mm, err_rad, max_iterations)  # pragma: no cover

    def wrist_angle(self, q: ArrayLike, data: Any = None) -> float:
        """Angle (rad, 0..pi/2) between the axes of joints 4 and 6: 0 is the wrist singularity
        (the two axes aligned, one rotation lost)."""
        pin = import_pinocchio()
        data = self.new_data() if data is None else data
        pin.forwardKinematics(self.model, data, np.asarray(q, dtype=np.float64))
        axes = []
        for j in (4, 6):  # Pinocchio joint ids: 0 is the universe
            joint = self.model.joints[j]
            local = joint_axis(joint)
            axes.append(data.oMi[j].rotation @ local)
        c = abs(float(axes[0] @ axes[1]))
        return math.acos(min(c, 1.0))

    def wrist_and_sigma(self, joints: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """:meth:`wrist_angle` and :meth:`sigma_min` of each row of ``joints`` (m, n), from the
        compiled chain in one call (the same figures to rounding)."""
        from seamtrack.control.arm_kernels import chain_figures

        q = np.ascontiguousarray(joints, dtype=np.float64).reshape(-1, self.dof)
        place, axes, kinds, index = self.chain
        where = {int(i): k for k, i in enumerate(index)}
        if 3 not in where or 5 not in where:  # joints 4 and 6 off the chain: one by one
            data = self.new_data()
            wrist = np.array([self.wrist_angle(x, data) for x in q])
            return wrist, np.array([self.sigma_min(x, data) for x in q])
        wrist = np.empty(len(q))
        jacobians = np.empty((len(q), 6, self.dof))
        chain_figures(q, place, axes, kinds, index, where[3], where[5], wrist, jacobians)
        if not len(q):
            return wrist, np.empty(0)
        sigma = np.linalg.svd(jacobians, compute_uv=False)[:, -1]
        return wrist, np.asarray(sigma, dtype=np.float64)

    def sigma_min(self, q: ArrayLike, data: Any = None) -> float:
        """Smallest singular value of the TCP Jacobian (linear rows in m/rad)."""
        data = self.new_data() if data is None else data
        _, J = self.jacobian(q, data)
        return float(np.linalg.svd(J, compute_uv=False)[-1])


def _chain(model: Any, tcp_id: int) -> tuple[Any, ...]:
    """The joints supporting the torch tip as arrays (see :attr:`ArmKinematics.chain`)."""
    frame = model.frames[tcp_id]
    joints = [int(j) for j in model.supports[frame.parentJoint]][1:]  # 0 is the universe
    place = np.empty((len(joints) + 1, 4, 4))
    axes = np.empty((len(joints), 3))
    kinds = np.zeros(len(joints), dtype=np.int64)
    index = np.array([int(model.idx_qs[j]) for j in joints], dtype=np.int64)
    for k, j in enumerate(joints):
        joint = model.joints[j]
        place[k] = model.jointPlacements[j].homogeneous
        short = joint.shortname()
        kinds[k] = 1 if "Prismatic" in short or short[-2:] in ("PX", "PY", "PZ") else 0
        axes[k] = joint_axis(joint)
    place[-1] = frame.placement.homogeneous
    return place, axes, kinds, index


def joint_axis(joint: Any) -> FloatArray:
    """Unit axis of a revolute or prismatic joint in its own frame (X/Y/Z or an arbitrary
    axis)."""
    short = joint.shortname()
    if short[-2:] in ("RX", "PX"):
        return np.array([1.0, 0.0, 0.0])
    if short[-2:] in ("RY", "PY"):
        return np.array([0.0, 1.0, 0.0])
    if short[-2:] in ("RZ", "PZ"):
        return np.array([0.0, 0.0, 1.0])
    extracted = getattr(joint.extract(), "axis", None)
    if extracted is not None:
        axis = np.asarray(extracted, dtype=np.float64)
        return axis / np.linalg.norm(axis)
    return np.array([0.0, 0.0, 1.0])
