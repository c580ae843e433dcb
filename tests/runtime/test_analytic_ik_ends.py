"""Closed-form IK of arms with fixed joints carrying rpy offsets: after the flange (a tool), before
the base and between the joints.

A UR5 with two fixed joints of rpy ``0.1 0.2 0.3`` after its flange once kept the derivation
busy for minutes (one before its base too): the exact cos/sin of those angles multiplied out in
the geometry's tool pose and the derivation expanded the coefficients built on it. Runs of
constants that fold are now folded to 50-digit numbers (symkin.symbolic.ik_geometry.fold_ik);
one before the first joint or after the last is applied to the target instead (AnalyticIK.pose_map),
so the joints are solved on the exact arm without its ends. Each derivation that could hang runs
in a child process whose timeout is a guard against a hang only; what is asserted is that every
returned solution reaches its target under the numeric reference FK (Robot.fkine).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from symkin import Robot, load
from symkin.model.ets import ETS
from symkin.model.kinematics import const_matrix

ROOT = Path(__file__).resolve().parents[2]
GUARD_S = 300  # generous: each child takes about 15 s
REACH = 1e-9  # max |fkine(q) - T| of every returned solution
RPY = "0.1 0.2 0.3"
XYZ = "0.01 0.02 0.03"
# The UR5's joint origins (xyz, rpy) as in examples/ur5.urdf (Universal Robots' DH parameters).
_UR5 = [
    ("0 0 0", "0 0 0"),
    ("0 0 0.089159", "1.5707963267948966 0 0"),
    ("-0.425 0 0", "0 0 0"),
    ("-0.39225 0 0", "0 0 0"),
    ("0 0 0.10915", "1.5707963267948966 0 0"),
    ("0 0 0.09465", "-1.5707963267948966 0 0"),
]
# The same rpy offsets as an ETS (a URDF origin is tx ty tz Rz(yaw) Ry(pitch) Rx(roll)).
RPY_ETS = "tx(0.01) ty(0.02) tz(0.03) Rz(0.3) Ry(0.2) Rx(0.1)"


def ur5_urdf(after: int, before: int = 0, between: dict[int, int] | None = None, rpy: str = RPY) -> str:
    """A UR5 (to tool0) with ``after`` fixed joints of origin XYZ/``rpy`` after tool0, ``before``
    before its base link, and ``between[k]`` before joint k."""
    between = between or {}
    links: list[str] = []
    joints: list[str] = []

    def link() -> str:
        links.append(f"l{len(links)}")
        return links[-1]

    def fixed(parent: str, xyz: str, rpy_: str) -> str:
        child = link()
        joints.append(
            f'<joint name="f{len(joints)}" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy_}"/></joint>'
        )
        return child

    at = link()
    for _ in range(before):
        at = fixed(at, XYZ, RPY)
    for k, (xyz, rpy_) in enumerate(_UR5):
        for _ in range(between.get(k, 0)):
            at = fixed(at, XYZ, rpy)
        child = link()
        joints.append(
            f'<joint name="j{k}" type="revolute"><parent link="{at}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy_}"/><axis xyz="0 0 1"/>'
            '<limit lower="-6.283185307179586" upper="6.283185307179586" velocity="3" effort="10"/></joint>'
        )
        at = child
    at = fixed(at, "0 0 0.0823", "0 0 0")  # tool0
    for _ in range(after):
        at = fixed(at, XYZ, RPY)
    body = "\n  ".join([f'<link name="{n}"/>' for n in links] + joints)
    name = f"ur5_fixed{after}_before{before}" + "".join(f"_at{k}x{c}" for k, c in sorted(between.items()))
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n  {body}\n</robot>\n'


def with_ends(name: str, before: int, after: int, *, sub: int | None = None) -> tuple[str, list]:
    """A built-in arm (or its sub-robot without joint ``sub``) with ``before`` and ``after`` copies
    of RPY_ETS around it: (ETS text, qlim)."""
    robot = load(name)
    if sub is not None:
        from symkin.runtime.free_joint import sub_robot

        robot = sub_robot(robot, sub)[0]
    text = " ".join([RPY_ETS] * before + [str(robot.ets)] + [RPY_ETS] * after)
    return text, np.asarray(robot.qlim).tolist()


CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import symkin
    from symkin import Robot
    from symkin.model.ets import ETS

    out = []
    for label, source, qlim, backends in json.loads(sys.stdin.read()):
        if qlim is None:
            robot = Robot.from_urdf(source)
        else:
            robot = Robot(ETS.parse(source), name=label, qlim=np.array(qlim))
        Q = robot.random_q(20, seed=5)
        T = robot.fkine(Q)
        rev = np.array([e.is_revolute for e in robot.ets.joints])
        for backend in backends:
            kin = symkin.compile(robot, backend)
            if not kin.has_analytic_ik:
                out.append([label, backend, False, None, None, None])
                continue
            batch = kin.ik_all(T, joint_limits=False)
            err, missing, fewest = 0.0, 0, kin.analytic.max_solutions
            for q, Ti, rows in zip(Q, T, batch):
                sols = rows[~np.isnan(rows[:, 0])]
                fewest = min(fewest, len(sols))
                if len(sols):
                    err = max(err, float(np.abs(robot.fkine(sols) - Ti).max()))
                d = np.where(rev, np.remainder(sols - q + np.pi, 2 * np.pi) - np.pi, sols - q)
                missing += not (len(sols) and (np.abs(d).max(axis=1) < 1e-7).any())
            out.append([label, backend, True, err, missing, fewest])
    print(json.dumps(out))
    """
)


def run_child(cases: list[tuple[str, str, list | None, list[str]]], tmp_path: Path) -> list:
    """(label, URDF text or ETS text, qlim for an ETS or None for a URDF, backends) per case ->
    [label, backend, has_analytic_ik, max FK error, targets whose q is missing, fewest solutions]."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SYMKIN_CACHE": str(tmp_path / "cache")}
    res = subprocess.run(
        [sys.executable, "-c", CHILD], input=json.dumps(cases),
        capture_output=True, text=True, env=env, cwd=ROOT, timeout=GUARD_S,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    results = json.loads(res.stdout.strip().splitlines()[-1])
    assert [(r[0], r[1]) for r in results] == [(c[0], b) for c in cases for b in c[3]]
    return results


def assert_solved(results: list) -> None:
    for label, backend, has, err, missing, fewest in results:
        assert has, (label, backend, "no closed form")
        assert err <= REACH, (label, backend, err)
        assert missing == 0, (label, backend, f"the generating q is missing for {missing} targets")
        assert fewest >= 1, (label, backend)


def test_ur5_with_rpy_fixed_joints_after_the_flange_and_before_the_base(tmp_path):
    layouts = [(2, 0), (3, 0), (4, 0), (0, 2), (4, 2)]
    cases = [(f"ur5_a{a}_b{b}", ur5_urdf(a, b), None, ["numpy", "c"]) for a, b in layouts]
    assert_solved(run_child(cases, tmp_path))


def test_rpy_fixed_joints_between_the_joints(tmp_path):
    """Turned about the next joint's axis the arm keeps its structure (solved on 50-digit axes);
    turned about other axes it loses it (refused, not hung)."""
    kept = ur5_urdf(2, 2, between={2: 2}, rpy="0 0 0.3")
    lost = ur5_urdf(0, 0, between={2: 2})
    results = run_child([("kept", kept, None, ["numpy", "c"]), ("lost", lost, None, ["numpy"])], tmp_path)
    assert_solved(results[:2])
    assert results[2][2] is False


def test_other_structures_with_rpy_ends(tmp_path):
    """A spherical wrist, a prismatic joint, a spherical shoulder (solved read from the tool) and
    arms with fewer than 6 joints (their tool point stays on the chain)."""
    cases = []
    for label, name, sub in [("puma", "puma560", None), ("stanford", "stanford", None),
                             ("panda_q6", "panda", 6), ("planar3", "planar3", None)]:  # fmt: skip
        text, qlim = with_ends(name, 2, 3, sub=sub)
        cases.append((label, text, qlim, ["numpy", "c"]))
    three = f"{RPY_ETS} Rz(q) tz(0.4) Ry(q) tx(0.3) Ry(q) tx(0.2) {RPY_ETS} {RPY_ETS}"
    cases.append(("position3", three, [[-2.5] * 3, [2.5] * 3], ["numpy", "c", "casadi"]))
    assert_solved(run_child(cases, tmp_path))


# -- the derivation (in process: each takes well under a second) -------------------------------
def _const_product(elements) -> np.ndarray:
    T = np.eye(4)
    for e in elements:
        T = T @ const_matrix(e.axis, e.const)
    return T


def test_ends_are_applied_to_the_target_and_the_arm_stays_exact():
    import sympy as sp

    from symkin.symbolic.analytic_ik import derive_analytic

    robot = Robot.from_urdf(ur5_urdf(3, 2))
    plan = derive_analytic(robot)
    bare = derive_analytic(Robot.from_urdf(ur5_urdf(0, 0)))
    assert plan.structure == bare.structure and plan.max_solutions == 8
    g = plan.geometry
    assert (g.h, g.p) == (bare.geometry.h, bare.geometry.p)  # exact, as without the ends
    assert not any(x.has(sp.Float) for v in g.h + g.p for x in v) and not g.M.has(sp.Float)
    ets = tuple(robot.ets)
    first = next(i for i, e in enumerate(ets) if e.is_joint)
    last = max(i for i, e in enumerate(ets) if e.is_joint)
    np.testing.assert_allclose(np.array(plan.base, dtype=float), _const_product(ets[:first]), atol=1e-15)
    np.testing.assert_allclose(np.array(plan.tool, dtype=float), _const_product(ets[last + 1 :]), atol=1e-15)
    pose = [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)] + ["px", "py", "pz"]
    assert [str(s) for s, _ in plan.pose_map] == pose
    # the verification pose is the whole arm's
    q = np.array([0.3, -1.1, 0.9, 0.4, -0.7, 1.3])
    values = {
        sp.Symbol(f"{a}{j}", real=True): f(q[j]) for j in range(6) for a, f in (("c", np.cos), ("s", np.sin))
    }
    fk = np.array([float(e.xreplace(values)) for e in plan.fk]).reshape(3, 4)
    np.testing.assert_allclose(fk, robot.fkine(q)[:3], atol=1e-12)


def test_an_arm_without_folded_ends_derives_as_before():
    from symkin.symbolic.analytic_ik import derive_analytic

    for name in ("ur5", "puma560", "planar2"):
        plan = derive_analytic(load(name))
        assert plan.base is None and plan.tool is None and plan.pose_map == ()
    one = Robot(ETS.parse(f"Rz(0.3) {load('ur5').ets} Rx(0.1)"), name="one_rotation_each_end")
    plan = derive_analytic(one)  # a single rotation at each end stays on the exact chain
    assert plan.base is None and plan.tool is None


def test_fewer_than_6_joints_move_only_the_tool_rotation():
    from symkin.symbolic.analytic_ik import derive_analytic

    text, qlim = with_ends("planar2", 2, 2)
    plan = derive_analytic(Robot(ETS.parse(text), name="planar2_ends", qlim=np.array(qlim)))
    assert plan.structure.kind == "planar2"
    tool = np.array(plan.tool, dtype=float)
    assert (tool[:3, 3] == 0).all() and np.abs(tool[:3, :3] - np.eye(3)).max() > 0.1
    assert abs(float(plan.geometry.M[0, 3]) - 2.0) < 0.1  # the tool point: links of 1 m plus the offsets


def test_derivation_document_names_the_ends():
    from symkin.derive.analytic_ik import ik_derivation

    text = ik_derivation(Robot.from_urdf(ur5_urdf(2, 2)))
    assert r"T_{\mathrm{base}}" in text and r"T_{\mathrm{tool}}" in text
    assert "0.75358981601014189" in text  # 17 digits shown, not 50


@pytest.mark.parametrize("layout", [(0, 1), (1, 0)])
def test_one_rpy_fixed_joint_is_folded_too(layout):
    from symkin.symbolic.analytic_ik import derive_analytic

    after, before = layout
    plan = derive_analytic(Robot.from_urdf(ur5_urdf(after, before)))
    assert (plan.base is not None) == bool(before) and (plan.tool is not None) == bool(after)
