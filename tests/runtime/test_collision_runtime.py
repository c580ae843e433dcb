"""Collision-aware IK, straight motions and MMC with obstacles (the NEO velocity damper)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import symkin
from symkin.errors import GeometryError, ParameterError
from symkin.geometry import Box, Capsule, Environment, Sphere

TABLE = Environment(
    spheres=(Sphere((0.45, 0.35, 0.25), 0.08),),
    capsules=(Capsule((0.4, -0.4, 0.0), (0.4, -0.4, 0.5), 0.05),),
    boxes=(Box((0.5, 0.0, -0.1), (0.5, 0.8, 0.05)),),
)


def _colliding_targets(panda, kin, count, seed=0):
    """Configurations without self-collision whose arm (not the wrist and hand) hits the table
    scene, and their poses: other arm postures reach the same pose."""
    rng = np.random.default_rng(seed)
    labels = kin.collision_pairs(TABLE)
    shapes = panda.geometry.shapes
    hand = np.array([k != "self" and shapes[i].link in ("link6", "link7", "ee") for k, i, _ in labels])
    out = []
    while len(out) < count:
        q = panda.random_q(seed=rng)
        d = kin.distances(q, TABLE)
        # the hand 5 cm clear of the scene beyond the covering spheres' outward excess (2 cm)
        if kin.in_collision(q, TABLE) and not kin.in_collision(q) and d[hand].min() > 0.07:
            out.append(q)
    Q = np.array(out)
    return Q, kin.fkine(Q)


def test_ik_rejects_colliding_solutions(panda, kin):
    Q, T = _colliding_targets(panda, kin, 8)
    for q, Tep in zip(Q, T):
        plain = kin.ik(Tep, q0=q, seed=1)
        assert plain.success and kin.in_collision(plain.q, TABLE)  # the start is a colliding solution
        aware = kin.ik(Tep, q0=q, seed=1, collision=TABLE)
        if aware.success:
            assert not kin.in_collision(aware.q, TABLE)
            assert np.abs(kin.fkine(aware.q) - Tep).max() < 1e-5
            assert aware.iterations > plain.iterations
        else:
            assert "in collision" in aware.reason
    solved = [kin.ik(Tep, q0=q, seed=1, collision=TABLE).success for q, Tep in zip(Q, T)]
    assert sum(solved) >= 6  # a redundant arm reaches most of these poses another way


def test_batch_ik_with_collision(panda, kin):
    Q, T = _colliding_targets(panda, kin, 6, seed=3)
    res = kin.ik(T, q0=Q, seed=2, collision=TABLE)
    assert res.q.shape == (6, 7) and len(res.reason) == 6
    ok = np.asarray(res.success)
    assert ok.sum() >= 4
    assert not kin.in_collision(res.q[ok], TABLE).any()
    assert np.abs(kin.fkine(res.q[ok]) - T[ok]).max() < 1e-5


def test_self_collision_only_and_bad_options(panda, kin):
    q = panda.qr
    res = kin.ik(kin.fkine(q), collision=True, seed=0)
    assert res.success and not kin.in_collision(res.q)
    with pytest.raises(ParameterError, match="collision_attempts"):
        kin.ik(kin.fkine(q), collision=TABLE, collision_attempts=0)
    far = np.eye(4)
    far[0, 3] = 5.0
    res = kin.ik(far, collision=TABLE, seed=0, slimit=3)
    plain = kin.ik(far, seed=0, slimit=3)
    assert not res.success and res.reason == plain.reason  # unreachable: as the plain solver says
    with pytest.raises(GeometryError):
        symkin.compile("puma560", backend="c").ik(np.eye(4), collision=True)


def test_motion_valid(panda, kin):
    # MoveIt's "ready" pose to symkin's qr (qz is outside the Panda's joint 4 limits)
    q0, q1 = np.array([0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4]), panda.qr.copy()
    assert not kin.in_collision(q0) and kin.motion_valid(q0, q1, TABLE) is True
    mid = 0.5 * (q0 + q1)
    hand = kin.fkine(mid)[:3, 3]
    wall = Environment(spheres=(Sphere(hand, 0.03),))
    assert not kin.in_collision(q0, wall) and not kin.in_collision(q1, wall)
    assert kin.motion_valid(q0, q1, wall) is False
    assert kin.motion_valid(q0, q0, wall) is True
    for bad in (0, -1, float("nan"), "fine"):
        with pytest.raises(ParameterError, match="resolution"):
            kin.motion_valid(q0, q1, wall, resolution=bad)


def _run(kin, controller, q0, Tep, env, steps=120, dt=0.05):
    q = q0.copy()
    closest = np.inf
    for _ in range(steps):
        nu, done = symkin.p_servo(kin.fkine(q), Tep, gain=1.0, threshold=0.01, frame="base")
        if done:
            break
        qd, _ = controller.step(q, nu)
        q = q + dt * qd
        closest = min(closest, float(kin.distances(q, env)[-len(kin.model.geometry.shapes) :].min()))
    return q, closest


def test_mmc_with_an_obstacle_never_enters_it(panda, kin):
    q0 = panda.qr.copy()
    T0 = kin.fkine(q0)
    Tep = T0.copy()
    Tep[1, 3] += 0.4
    centre = 0.5 * (T0[:3, 3] + Tep[:3, 3])
    env = Environment(spheres=(Sphere(centre, 0.05),))
    assert kin.distances(q0, env)[-len(panda.geometry.shapes) :].min() > 0.05
    _, closest_plain = _run(kin, symkin.MMC(kin), q0, Tep, env)
    assert closest_plain < 0  # the straight path goes through the obstacle
    for backend in ("c", "python"):
        mmc = symkin.MMC(kin, collision=env, d_i=0.3, d_s=0.02, backend=backend)
        assert mmc.backend == backend and mmc.slack
        q, closest = _run(kin, mmc, q0, Tep, env)
        assert closest > 0  # never enters the obstacle (nor its 2 cm safety margin, up to the step size)
        assert np.linalg.norm(kin.fkine(q)[:3, 3] - Tep[:3, 3]) < np.linalg.norm(T0[:3, 3] - Tep[:3, 3])
    # the C servo loop with the C collision step
    run = symkin.servo(kin, q0, Tep, mmc := symkin.MMC(kin, collision=env, d_i=0.3, d_s=0.02), max_steps=200)
    assert mmc.backend == "c"
    shapes = len(panda.geometry.shapes)
    assert kin.distances(run.q, env)[:, -shapes:].min() > 0 and run.arrived
    qp = mmc.build(q0, np.zeros(6))
    assert qp.n_distance == 32  # the closest pairs within d_i, padded with free rows
    d = kin.distances(q0, env)
    is_self = np.array([kind == "self" for kind, _, _ in kin.collision_pairs(env)])
    within = np.where(is_self, d < 0.05, d < 0.3)  # self pairs: d_i_self (0.05)
    assert np.isfinite(qp.l[6 + 7 :]).sum() == min(32, within.sum()) and (within & ~is_self).any()
    with pytest.raises(ParameterError, match="d_i_self"):
        symkin.MMC(kin, collision=env, d_i_self=0.01, d_s_self=0.02)
    with pytest.raises(ParameterError, match="d_i"):
        symkin.MMC(kin, collision=env, d_i=0.01, d_s=0.05)
    with pytest.raises(ParameterError, match="collision_rows"):
        symkin.MMC(kin, collision=env, collision_rows=0)


def test_c_mmc_with_obstacles_solves_the_python_qp(panda, kin):
    """The C step with obstacle rows (one C call: distances, the closest pairs' dampers, the active-set
    solve with the rows or OSQP and its polish) against the Python step building the same QP from
    the collision kernel, and against OSQP at tight tolerances on that QP (another algorithm)."""
    osqp = pytest.importorskip("osqp")
    sp = pytest.importorskip("scipy.sparse")
    q0 = panda.qr.copy()
    T0 = kin.fkine(q0)
    Tep = T0.copy()
    Tep[:3, 3] += (0.1, 0.4, -0.1)
    env = Environment(
        spheres=(Sphere(0.5 * (T0[:3, 3] + Tep[:3, 3]), 0.06),),
        capsules=(Capsule((0.2, -0.4, 0.0), (0.2, -0.4, 0.6), 0.04),),
    )
    options = {"d_i": 0.3, "d_s": 0.02, "collision_rows": 12, "qd_max": 1.5, "joint_limits": True}
    c = symkin.MMC(kin, collision=env, **options)
    p = symkin.MMC(kin, collision=env, backend="python", **options)
    assert c.backend == "c" and p.backend == "python"
    q, near, methods, warm = q0.copy(), 0, [], 0
    for k in range(80):
        nu, done = symkin.p_servo(kin.fkine(q), Tep, gain=1.0, threshold=0.01, frame="base")
        if done:
            break
        (a, ia), (b, ib) = c.step(q, nu), p.step(q, nu)
        assert (ia.status, ia.fallback) == (ib.status, ib.fallback) == ("solved", None), (ia, ib)
        assert np.abs(a - b).max() <= 1e-8 * max(1.0, np.abs(b).max()), (ia, ib)  # both exact
        qp = p.build(q, nu)
        rows, lower = qp.A[6 + 7 :, :7], qp.l[6 + 7 :]
        active = np.isfinite(lower)
        if active.any():
            near += 1
            methods.append(ia.method)
            warm += ia.method == "active_set" and ia.iterations == 1  # the last step's set held
            assert (rows[active] @ a >= lower[active] - 1e-8).all()  # the dampers hold
            if k % 5 == 0:
                solver = osqp.OSQP()
                solver.setup(
                    sp.csc_matrix(qp.P), qp.c, sp.csc_matrix(qp.A), np.maximum(qp.l, -1e30),
                    np.minimum(qp.u, 1e30), eps_abs=1e-11, eps_rel=1e-11, max_iter=200_000, verbose=False,
                )  # fmt: skip
                ref = solver.solve(raise_error=False)
                assert ref.info.status == "solved"
                # the QP can be flat along some directions (the covering model's many close pairs):
                # compare what a QP solver guarantees, the optimal value and feasibility, with the
                # slack of the C step taken from the equality rows
                x = ref.x.copy()
                x[:7] = a
                x[7:] = np.linalg.lstsq(qp.A[:6, 7:], qp.l[:6] - qp.A[:6, :7] @ a, rcond=None)[0]
                Ax = qp.A @ x
                assert max((qp.l - Ax).max(), (Ax - qp.u).max()) < 1e-9  # feasible
                ours, theirs = (0.5 * v @ qp.P @ v + qp.c @ v for v in (x, ref.x))
                assert ours <= theirs + 1e-10 * max(1.0, abs(theirs))  # as low as OSQP's
        lo, hi = p.bounds(q)
        assert (a >= lo - 1e-12).all() and (a <= hi + 1e-12).all()
        q = q + 0.05 * b
    assert near >= 5 and methods.count("active_set") >= 0.8 * near and warm >= 0.5 * near


def test_mmc_collision_backends_and_self_collision(panda, kin):
    # self-collision only (collision=True) runs in C too; without the slack it stays in Python
    # (the sphere model's closest self pair at qr is 1.2 cm apart: within d_i_self, above d_s_self;
    # with the obstacles' d_s = 0.05 it would have to part at every step)
    nu, options = np.r_[0.05, 0, 0, 0, 0, 0], {"collision": True}
    (qd, info), (ref, rinfo) = (
        symkin.MMC(kin, **options, backend=b).step(panda.qr, nu) for b in ("c", "python")
    )
    assert info.ok and rinfo.ok and info.method == rinfo.method and np.abs(qd - ref).max() < 1e-9
    assert symkin.MMC(kin, collision=TABLE).backend == "c"
    assert symkin.MMC(kin, collision=TABLE, slack=False).backend == "python"
    with pytest.raises(symkin.errors.ConfigurationError, match="slack"):
        symkin.MMC(kin, collision=TABLE, slack=False, backend="c")
    assert symkin.MMC(symkin.compile(panda, backend="numpy"), collision=TABLE).backend == "python"
    with pytest.raises(GeometryError):
        symkin.MMC(kin, collision=[1.0])


def test_collision_ik_is_reproducible_with_a_seed(panda, kin):
    Q, T = _colliding_targets(panda, kin, 4, seed=5)
    a = kin.ik(T, q0=Q, seed=9, collision=TABLE)
    b = kin.ik(T, q0=Q, seed=9, collision=TABLE)
    assert np.array_equal(a.q, b.q) and a.reason == b.reason
    one = kin.ik(T[0], q0=Q[0], seed=9, collision=TABLE)
    assert one.q.shape == (7,) and isinstance(one.reason, str)
    assert np.all(np.asarray(a.iterations) >= np.asarray(kin.ik(T, q0=Q, seed=9).iterations))


def test_c_solver_rejects_colliding_solutions_inside_its_search_loop(panda, kin):
    """On compiled C kinematics kin.ik(collision=env) is one C solve whose search loop asks the
    collision kernel about every converged solution: a colliding one is rejected and the next
    search starts. Inside a shell of obstacles every solution collides: the reason counts the
    rejected ones, and the NumPy backend (rounds of Python restarts) fails the same target too."""
    from symkin.runtime.collision import collision_solver

    assert collision_solver(kin, TABLE, {"seed": 1}) is not None
    numpy_kin = symkin.compile(panda, backend="numpy")
    assert collision_solver(numpy_kin, TABLE, {}) is None
    Tep = kin.fkine(panda.qr)
    hand = Tep[:3, 3]
    cage = Environment(spheres=(Sphere(hand + [0.0, 0.0, -0.25], 0.12),))  # around the forearm's way
    plain = kin.ik(Tep, seed=4, slimit=4)
    res = kin.ik(Tep, seed=4, slimit=4, collision=Environment(spheres=(Sphere((0, 0, 0.5), 2.0),)))
    assert plain.success and not res.success
    assert re.search(r"; [1-4] converged solution\(s\) rejected: in collision", res.reason), res.reason
    free = kin.ik(Tep, seed=4, collision=cage)
    assert free.success and not kin.in_collision(free.q, cage)
    assert np.abs(kin.fkine(free.q) - Tep).max() < 1e-5
    slow = numpy_kin.ik(Tep, seed=4, slimit=4, collision=Environment(spheres=(Sphere((0, 0, 0.5), 2.0),)))
    assert not slow.success and slow.reason == "in collision"


def test_one_target_avoiding_collisions_is_one_c_call_after_the_first(panda, kin, monkeypatch):
    """kin.ik(T, collision=env) makes its C solver once; later calls with the same options, and an
    equal environment, go from kin.ik's C entry point straight to that solver (no Python path:
    collision_solver is not called again) and give what the solver gives."""
    import symkin.runtime.collision as collision

    T = kin.fkine(panda.qr)
    env = Environment(spheres=(Sphere((0.5, 0.3, 0.3), 0.1), Sphere((0.2, -0.4, 0.6), 0.1)))
    first = kin.ik(T, seed=3, collision=env)
    expected = collision.collision_solver(kin, env, {}).solve(T, seed=3)
    monkeypatch.setattr(collision, "collision_solver", lambda *a, **k: pytest.fail("the Python path"))
    again = kin.ik(T, seed=3, collision=Environment(spheres=env.spheres))
    assert first.success and np.array_equal(first.q, again.q) and np.array_equal(again.q, expected.q)
    assert not kin.in_collision(again.q, env)
    batch = kin.ik(np.stack([T, T]), seed=3, collision=env)  # a batch with those options: its solver too
    assert batch.success.all() and not kin.in_collision(batch.q, env).any()
