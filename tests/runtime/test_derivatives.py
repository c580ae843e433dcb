"""``kin.derivative(q, order, frame)`` of the compiled kinematics on every backend: against the
numeric reference (Part 2's recursion) and central differences of J0 of order k - 1, for
built-in chains, a chain's link frames, trees and a mimic-joint tree; batches; compiled with
``derivatives=k`` or on the first call; the generated C as strict C99/C++ in both precisions;
the errors."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import symkin
from symkin import ConfigurationError, FrameError, ParameterError, Tree
from tests.conftest import assert_close
from tests.model.test_derivatives import FD_TOL, central_differences
from tests.model.tree_urdfs import GRIPPER, QUADRUPED

BACKENDS = ("c", "numpy", "casadi")


@pytest.fixture(scope="module")
def panda_kin():
    panda = symkin.load("panda")
    return panda, {b: symkin.compile(panda, b, derivatives=4) for b in BACKENDS}


@pytest.mark.parametrize("backend", BACKENDS)
def test_panda_orders_one_to_four_match_the_reference_and_differences(panda_kin, backend):
    panda, kins = panda_kin
    kin = kins[backend]
    assert "derivative4" in kin.__dict__ and "derivative3" in kin.__dict__  # compiled up front
    Q = panda.random_q(4, seed=11)
    for order in (1, 2, 3, 4):
        D = kin.derivative(Q, order)
        assert D.shape == (4,) + (7,) * (order - 1) + (6, 7)
        assert_close(D, panda.derivative(Q, order), 1e-14, f"{backend} order {order}")
        assert_close(D[0], central_differences(panda.jacob0, Q[0], order), FD_TOL[order], f"FD {order}")
        assert_close(kin.derivative(Q[1], order), D[1], 0.0, "one configuration = its row of the batch")
    assert_close(kin.derivative(Q, 2), kin.hessian0(Q), 0.0, "order 2 is hessian0")
    assert kin.derivative(np.zeros((0, 7)), 3).shape == (0, 7, 7, 6, 7)


@pytest.mark.parametrize("backend", BACKENDS)
def test_link_frames_of_a_compiled_chain(panda_kin, backend):
    panda, kins = panda_kin
    q = panda.random_q(seed=12)
    for k in (0, 4):
        D = kins[backend].derivative(q, 3, frame=k)
        assert_close(D, panda.derivative(q, 3, frame=k), 1e-14, f"link {k}")


@pytest.mark.parametrize("name", ["planar3", "stanford", "cobra600"])  # prismatic joints in the last two
def test_other_chains_compiled_on_first_call(name):
    robot = symkin.load(name)
    kin = symkin.compile(robot, "c")
    assert "derivative3" not in kin.__dict__
    q = robot.random_q(seed=13)
    D = kin.derivative(q, 3)  # compiles the derivatives up to order 3 on this call
    assert "derivative3" in kin.__dict__
    assert_close(D, robot.derivative(q, 3), 1e-14, name)
    assert_close(D, central_differences(robot.jacob0, q, 3), FD_TOL[3], f"{name} FD")
    for backend in ("numpy", "casadi"):
        assert_close(symkin.compile(robot, backend).derivative(q, 3), D, 1e-14, f"{name} {backend}")


@pytest.mark.parametrize("urdf", [QUADRUPED, GRIPPER], ids=["quadruped", "gripper-mimic"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_tree_frames_and_mimic_joints(urdf, backend):
    tree = Tree.from_urdf(urdf)
    kin = symkin.compile(tree, backend, derivatives=4)
    Q = tree.random_q(3, seed=14)
    for frame in tree.frames:
        for order in (3, 4):
            D = kin.derivative(Q, order, frame)
            assert_close(D, tree.derivative(Q, order, frame), 1e-14, f"{frame} order {order}")
            J = lambda X, f=frame: tree.jacob0(X, f)  # noqa: E731
            assert_close(D[0], central_differences(J, Q[0], order), FD_TOL[order], f"{frame} FD")
    with pytest.raises(FrameError, match="name one with frame="):
        kin.derivative(Q, 3)
    with pytest.raises(FrameError, match="no frame"):
        kin.derivative(Q, 3, "nowhere")


@pytest.mark.parametrize("backend", BACKENDS)
def test_errors(panda_kin, backend):
    panda, kins = panda_kin
    kin = kins[backend]
    with pytest.raises(ParameterError, match="order must be 1"):
        kin.derivative(panda.qz, 9)
    with pytest.raises(ParameterError, match="order must be an integer"):
        kin.derivative(panda.qz, 3.0)
    with pytest.raises(ConfigurationError):
        kin.derivative(np.full(7, np.nan), 3)
    with pytest.raises(ConfigurationError):
        kin.derivative(np.zeros(6), 4)
    with pytest.raises(FrameError):
        kin.derivative(panda.qz, 3, frame=7)
    with pytest.raises(symkin.SymkinError, match="derivatives must be an integer 0..8"):
        symkin.compile(panda, backend, derivatives=9)


def test_default_compile_has_no_derivative_code():
    files = symkin.generate(symkin.load("ur5"), "c")
    assert "derivative" not in "".join(files.values())
    more = symkin.generate(symkin.load("ur5"), "c", derivatives=3)
    text = more["symkin_ur5.c"]
    assert "symkin_ur5_derivative3(" in text and "derivative3_D_at_" in text  # gathered: a table


CC = shutil.which("cc") or shutil.which("gcc")
CXX = shutil.which("c++") or shutil.which("g++")
STRICT = ["-Wall", "-Wextra", "-pedantic", "-Werror"]


@pytest.mark.skipif(CC is None or CXX is None, reason="no C/C++ compiler")
def test_generated_derivatives_are_strict_c_and_cpp_in_both_precisions(tmp_path):
    tree = Tree.from_urdf(GRIPPER)
    for precision in ("double", "float"):
        files = symkin.generate(tree, "c", precision=precision, prefix="grip", derivatives=4)
        for name, text in files.items():
            (tmp_path / name).write_text(text)
        for cmd in ([CC, "-std=c99"], [CXX, "-std=c++11", "-x", "c++"]):
            proc = subprocess.run([*cmd, *STRICT, "-c", "grip.c", "-o", "/dev/null"], cwd=tmp_path,
                                  capture_output=True, text=True)  # fmt: skip
            assert proc.returncode == 0, proc.stderr
