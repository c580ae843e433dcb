"""The public sympy expressions of a robot's kinematics: ``symkin.symbolic(robot)``.

``form="expanded"`` gives every entry as one exact expression of the joint symbols ``q0 ..
q{n-1}`` (the same expressions the compiler starts from, :func:`symkin.symbolic.kinematics.derive`):
rotations about one axis are merged (``cos(q1 + q2)``), constants stay exact (``pi/2``, ``333/1000``).
Their size grows quickly with the length of the chain: a 6-joint arm's Jacobian is readable, a
generic 12-joint chain's multiplied-out pose and Jacobian have about two million nodes (sympy shares
the subtrees, so building them is cheap, but printing, ``simplify`` or ``lambdify`` are not).

``form="program"`` gives the same quantities as a straight-line program
(:func:`symkin.symbolic.program.derive_program`): ``lines`` assigns named intermediates ``t0, t1,
...`` in order (each a short expression of the joint symbols and earlier names), and ``T``, ``J0``,
``Je``, ``H0``, ``He`` are matrices over those names; the size grows linearly with the chain. The
written derivation of that form is ``symkin.derive_steps(robot, form="program")``.
"""

from __future__ import annotations

from typing import Any

from symkin.errors import check_choice
from symkin.model.ets import ETS
from symkin.model.robot import Robot

__all__ = ["symbolic", "FORMS"]

FORMS = ("expanded", "program")


def symbolic(robot: Robot | ETS | str, form: str = "expanded") -> Any:
    """The exact sympy kinematics of ``robot`` (a Robot, an ETS, or any ROBOT spec such as ``"ur5"``).

    Returns an object with ``q`` (the joint symbols ``q0 .. q{n-1}``, real), ``T`` (4x4 pose of the
    end effector in the base frame, eq 1 of Haviland and Corke, Manipulator Differential
    Kinematics, Part 1, 2023), ``J0`` and ``Je`` (6xn base- and end-effector-frame Jacobians, rows
    (v, omega), eqs 14-16 and 31-34), ``H0`` and ``He`` (n matrices 6xn, ``H[i] = dJ/dq_i``,
    Haviland and Corke, Maximising Manipulability During Resolved-Rate Motion Control, 2020, eq 20)
    and ``links`` (the pose right after each joint, chain order). ``form="program"`` adds ``lines``,
    the named intermediates the matrices are written in (see the module docstring).
    """
    check_choice(form, FORMS, "form")
    from symkin.model.resolve import robot_with_joints

    robot = robot_with_joints(robot)
    from symkin.symbolic.kinematics import const_to_sympy, derive, joint_symbols

    if form == "expanded":
        return derive(robot)
    from symkin.symbolic.program import derive_program

    return derive_program(robot.ets, joint_symbols(robot.n), const_to_sympy, robot.name, hessians=True)
