"""The servo loop: position-based servoing (Haviland and Corke, Manipulator Differential Kinematics, Part 1,
2023, eqs 37-43) driven by RRMC, QRMC or MMC, integrated in time."""

from __future__ import annotations

import dataclasses
import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.core.arrays import MAX_JOINT_VALUE, as_config, name_of
from symkin.core.pose import pose_array
from symkin.errors import ConfigurationError, ParameterError, PoseError
from symkin.runtime.control import MMC, StepInfo, rrmc_controller, servo_rrmc_step
from symkin.runtime.ik import check_pose, pose_error_of
from symkin.runtime.qrmc import QRMC
from symkin.runtime.servo import check_threshold, servo_gain, servo_velocity, velocity_caps
from symkin.runtime.task import task_kinematics

__all__ = ["servo", "ServoResult", "SERVO_HALVINGS"]

#: The most times a servo run with collision rows halves a step whose end the collision checker
#: calls colliding before it stops (``csrc/mmc_py.c``: SERVO_HALVINGS).
SERVO_HALVINGS = 10

Controller = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, StepInfo]]


@dataclass(frozen=True, eq=False)
class ServoResult:
    """A servo run of ``steps`` control steps.

    Attributes:
        q: (steps + 1, n) configurations, ``q[0] = q0``, ``q[k + 1] = q[k] + dt qd[k]``.
        qd: (steps, n) joint velocities.
        e: (steps + 1, 6) base-frame pose error (eq 37) at each configuration.
        manipulability: (steps + 1,) manipulability of the controller's axes at each configuration.
        info: per step, how the controller found qd (:class:`StepInfo`).
        step_time: (steps,) seconds spent in the controller per step (kinematics and solve), perf_counter.
        arrived: whether ``sum |e| < threshold`` was reached within ``max_steps``.
        limit_violations: number of configurations ``q[1:]`` with a joint outside ``qlim``.
        dt: the time step (s).
        controller: ``"mmc"``, ``"rrmc"``, ``"qrmc"`` or the controller's name.
        blocked: the run stopped because no part of the next step was free of collision (an MMC with
            collision rows: every configuration the loop returns passes the collision checker,
            ``kin.in_collision(q, env)``; a step whose end it calls colliding is halved, up to
            :data:`SERVO_HALVINGS` times, and ``info[k].scale`` says by how much).
    """

    q: np.ndarray
    qd: np.ndarray
    e: np.ndarray
    manipulability: np.ndarray
    info: tuple[StepInfo, ...]
    step_time: np.ndarray
    arrived: bool
    limit_violations: int
    dt: float
    controller: str
    blocked: bool = False

    @property
    def steps(self) -> int:
        return self.qd.shape[0]

    @property
    def t(self) -> np.ndarray:
        """(steps + 1,) time of each configuration (s)."""
        return np.arange(self.steps + 1) * self.dt

    @property
    def status(self) -> tuple[str, ...]:
        """Solver status of each step."""
        return tuple(i.status for i in self.info)

    @property
    def reason(self) -> str:
        """Why the run ended: ``"arrived"``, ``"collision"`` (:attr:`blocked`) or ``"max_steps"``."""
        return "arrived" if self.arrived else "collision" if self.blocked else "max_steps"

    @property
    def left_limits(self) -> bool:
        """True when some configuration left the joint limits."""
        return self.limit_violations > 0

    @property
    def mean_manipulability(self) -> float:
        return float(self.manipulability.mean())

    @property
    def final_manipulability(self) -> float:
        return float(self.manipulability[-1])

    def __repr__(self) -> str:
        return (
            f"ServoResult(controller={self.controller!r}, steps={self.steps}, reason={self.reason!r}, "
            f"mean_manipulability={self.mean_manipulability:.4g}, limit_violations={self.limit_violations})"
        )


def servo(
    kin: Any,
    q0: Any,
    Tep: Any,
    controller: str | MMC | Controller = "mmc",
    dt: float = 0.05,
    gain: float | Any = 1.0,
    threshold: float = 0.1,
    max_steps: int = 500,
    lam: float = 0.005,
    qd_max: Any = None,
    joint_limits: bool = False,
    axes: str = "all",
    nu_max: Any = None,
    progress: bool = False,
    backend: str = "auto",
    frame: Any = None,
) -> ServoResult:
    """Servo the end effector from configuration ``q0`` (n,) to the base-frame pose ``Tep`` (4, 4).

    Each step: ``e`` from eq 37 at ``fkine(q)``; stop when ``sum |e| < threshold``; else
    ``nu = k e`` (eq 41-42, ``gain`` a number, ``(k_t, k_r)`` or six values; capped by ``nu_max`` as in
    :func:`symkin.runtime.servo.p_servo`), ``qd`` from the controller and ``q += dt qd``; at most
    ``max_steps`` steps. The protocol of the MMC paper's experiments is the default: gain 1, dt 0.05 s,
    threshold 0.1.

    ``controller`` is ``"mmc"`` (a new :class:`MMC` with ``lam``, ``qd_max``, ``joint_limits``,
    ``axes`` and ``dt``), ``"rrmc"`` (:func:`rrmc` with ``qd_max``), ``"qrmc"`` (a new
    :class:`~symkin.runtime.qrmc.QRMC` with ``qd_max`` and ``axes``: quadratic-rate control over a
    horizon of 1 s, each step also started from the last step's answer), an :class:`MMC` or ``QRMC``
    to reuse (its own options apply; a QRMC starts the run cold), or any callable ``(q, nu) -> (qd,
    StepInfo)``; ``kin`` needs ``n``, ``qlim``,
    ``fkine``, ``manipulability(q, axes)`` and what the controller uses. ``qd_max=None`` uses
    ``kin.qd_max`` when the robot has it; pass ``np.inf`` for no speed limit.

    ``backend``: ``"auto"`` (default) runs the whole loop in C (``csrc/mmc_py.c``: kinematics, pose
    error, velocity command and the controller's C step, with the same arithmetic) when ``kin`` is
    compiled C kinematics and the controller is ``"rrmc"``, ``"qrmc"`` or an MMC or QRMC whose step
    runs in C; ``"python"``
    runs this loop in Python around the same step; ``"c"`` requires the C loop. ``step_time`` is then
    the time of the C step alone.

    ``frame`` picks the frame that servos: a tree's frame name (:class:`symkin.Tree` or its compiled
    kinematics), or link frame k of a chain; the joints off its path do not move (the loop then
    runs in Python, except for a C tree's frame without mimic joints).

    With an :class:`MMC` with collision rows (``MMC(kin, collision=env)``) every configuration the run
    returns is free by the collision checker, ``kin.in_collision(q, env)`` (the dampers act on a
    linearisation, so a full step can end a few micrometres inside a pair): a step whose end
    collides is halved, up to :data:`SERVO_HALVINGS` times (``info[k].scale`` records it), and when
    no halving is free the run stops (``blocked``, ``reason == "collision"``). ``q0`` itself must
    be free: ConfigurationError naming the pair otherwise.
    """
    kin = task_kinematics(kin, frame)  # a chain itself, or one frame of a model
    if backend not in ("auto", "c", "python"):
        raise ParameterError(f"backend must be 'auto', 'c' or 'python', not {backend!r}")
    n = int(kin.n)
    q = as_config(q0, n, name_of(kin), "q0").copy()
    if not (isinstance(dt, numbers.Real) and math.isfinite(dt) and dt > 0):
        raise ParameterError(f"dt must be a positive finite number, got {dt!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral) or max_steps < 0:
        raise ParameterError(f"max_steps must be an integer >= 0, got {max_steps!r}")
    T = pose_array(Tep) if isinstance(Tep, np.ndarray) else None  # converted as check_pose does
    if T is None or T.shape != (4, 4):  # the C loop checks the pose itself
        T_all, single = check_pose(Tep)  # PoseError for NaN, a wrong shape or a non-SE(3) matrix
        if not single:
            raise PoseError(f"servo takes one target pose (4, 4), got shape {np.shape(Tep)}")
        T = T_all[0]
    k = [float(gain)] * 6 if type(gain) in (int, float) and 0 <= gain < math.inf else servo_gain(gain)
    check_threshold(threshold)
    velocity_caps(nu_max)  # checked before the loop starts
    step, name, cstep = _controller(kin, controller, lam, qd_max, joint_limits, axes, dt)
    guard = _collision_guard(getattr(step, "__self__", None), n)
    if guard is not None:
        _start_free(guard, q)
    if isinstance(controller, (MMC, QRMC)):
        axes = controller.axes
    if backend == "c" and cstep is None:
        raise ConfigurationError(
            "backend='c' needs compiled C kinematics and controller 'rrmc', 'qrmc', 'mmc' or an MMC or "
            "QRMC running in C"
        )
    if cstep is not None and backend != "python":
        bar = _progress(progress, max_steps, name)
        collide = None if guard is None else _c_collide(*guard)
        out = cstep.servo(T, q, k, threshold, dt, nu_max, axes, max_steps, collide)
        if out is None:  # not a valid pose
            check_pose(T)  # the detailed PoseError
            raise PoseError("invalid target pose")  # pragma: no cover - check_pose raised
        Qa, QDa, Ea, Ma, infos_c, times_c, arrived, viol, blocked = out
        if bar is not None:
            bar.update(len(QDa))
            bar.close()
        return ServoResult(
            Qa, QDa, Ea, Ma, infos_c, times_c, bool(arrived), int(viol), float(dt), name, bool(blocked)
        )
    check_pose(T)
    Tep = T
    k = np.asarray(k)
    qlo, qhi = np.asarray(kin.qlim, dtype=float)

    Q, QD, E, M, infos, times = [q.copy()], [], [], [], [], []
    arrived = blocked = False
    bar = _progress(progress, max_steps, name)
    try:
        for _ in range(max_steps + 1):
            e = pose_error_of(kin.fkine(q), Tep)
            E.append(e)
            nu, arrived = servo_velocity(e, k, threshold, nu_max)
            if arrived or len(QD) == max_steps:
                break
            t0 = time.perf_counter()
            qd, info = step(q, nu)
            elapsed = time.perf_counter() - t0
            q_next = q + dt * qd
            if guard is not None:
                q_next, qd, info = _accepted(guard, q, q_next, qd, info, dt)
                if q_next is None:  # no part of the step is free: not taken
                    blocked = True
                    break
            times.append(elapsed)
            M.append(info.manipulability)
            QD.append(qd)
            infos.append(info)
            q = q_next
            Q.append(q)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    M.append(float(kin.manipulability(q, axes=axes)))
    Qa, QDa = np.array(Q), np.array(QD).reshape(len(QD), n)
    viol = int((((Qa[1:] < qlo) | (Qa[1:] > qhi)).any(axis=1)).sum())
    M = np.array(M, dtype=float)
    return ServoResult(
        Qa, QDa, np.array(E), M, tuple(infos), np.array(times), arrived, viol, float(dt), name, blocked
    )


def _controller(
    kin: Any, controller: Any, lam: float, qd_max: Any, joint_limits: bool, axes: str, dt: float
) -> tuple[Controller, str, Any]:
    """(step, name, the C controller whose servo loop runs in C, or None)."""
    if isinstance(controller, str) and controller == "mmc":
        controller = MMC(kin, lam=lam, qd_max=qd_max, axes=axes, joint_limits=joint_limits, dt=dt)
    if isinstance(controller, MMC):
        cstep = controller._c if controller.kin is kin else None
        return controller.step, "mmc", cstep
    if isinstance(controller, str) and controller in ("rrmc", "qrmc"):
        if joint_limits:
            raise ParameterError(
                f"joint_limits=True needs controller='mmc' ({controller.upper()} has no joint-limit handling)"
            )
        if controller == "qrmc":
            controller = QRMC(kin, qd_max=qd_max, axes=axes)
        else:
            return servo_rrmc_step(kin, qd_max, axes), "rrmc", rrmc_controller(kin, qd_max, axes=axes)
    if isinstance(controller, QRMC):
        controller.reset()  # a run starts cold
        return controller.step, "qrmc", controller._c if controller.kin is kin else None
    if callable(controller):
        return controller, getattr(controller, "__name__", type(controller).__name__), None
    raise ParameterError(
        f"controller must be 'mmc', 'rrmc', 'qrmc', an MMC or QRMC, or a callable, not {controller!r}"
    )


def _progress(progress: bool, total: int, name: str) -> Any:
    from symkin.core.progress import bar, progress_shown

    if not progress_shown(progress):
        return None
    return bar(total=total, desc=f"servo ({name})")


# -- the step's acceptance with collision rows (issue 36, item 4) --------------------------------
def _collision_guard(mmc: Any, n: int) -> tuple[Any, Any] | None:
    """(collision checker, environment) of an MMC with collision rows whose checker takes the loop's
    n joint values, else None."""
    check = getattr(mmc, "_collision", None) if isinstance(mmc, MMC) else None
    if check is None or int(check.n) != n:
        return None
    return check, mmc._env


def _collides(guard: tuple[Any, Any], q: np.ndarray) -> bool:
    """Whether q is not acceptable: colliding by the checker, or not a valid configuration (the C
    kernel's -1: NaN, inf or beyond +-1e15)."""
    check, env = guard
    if not (np.abs(q) <= MAX_JOINT_VALUE).all():
        return True
    return bool(check.in_collision(q, env))


def _start_free(guard: tuple[Any, Any], q: np.ndarray) -> None:
    """ConfigurationError naming the deepest pair when the run's first configuration collides."""
    if not _collides(guard, q):
        return
    check, env = guard
    d = np.asarray(check.distances(q, env))
    i = int(np.argmin(d))
    kind, a, b = check.labels(env)[i]
    pair = f"self pair of shapes {a} and {b}" if kind == "self" else f"shape {a} and {kind} obstacle {b}"
    raise ConfigurationError(
        f"q0 is in collision ({pair}, signed distance {d[i]:.3g} m): a servo run with collision "
        "avoidance starts from a configuration that kin.in_collision(q0, env) calls free"
    )


def _accepted(
    guard: tuple[Any, Any], q: np.ndarray, q_next: np.ndarray, qd: np.ndarray, info: StepInfo, dt: float
) -> tuple[np.ndarray | None, np.ndarray, StepInfo]:
    """The step q -> q_next = q + dt qd, halved until the checker calls its end free (at most
    :data:`SERVO_HALVINGS` times; qd and ``info.scale`` halved with it, exactly: a power of two),
    as the C loop does; (None, qd, info) when no halving is free."""
    scale, h = 1.0, 0
    while _collides(guard, q_next):
        if h == SERVO_HALVINGS:
            return None, qd, info
        h += 1
        scale *= 0.5
        qd = qd * 0.5
        q_next = q + dt * qd
    if h:
        info = dataclasses.replace(info, scale=info.scale * scale)
    return q_next, qd, info


def _c_collide(check: Any, env: Any) -> tuple[int, int] | None:
    """The C loop's ``collide`` argument of a collision checker: the addresses of its kernel's
    ``skcoll_in_collision_packed`` and of the packed obstacles (kept alive by ``env``)."""
    from symkin.runtime.cext import address
    from symkin.runtime.collision import env_args

    kernel = getattr(check, "kernel", None)
    if kernel is None:  # pragma: no cover - a C MMC with collision rows has the C kernel
        raise ConfigurationError("the C servo loop with collision rows needs the C collision kernel")
    return address(kernel.lib.skcoll_in_collision_packed), int(env_args(env).address)
