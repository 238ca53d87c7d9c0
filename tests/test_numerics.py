"""CPU-independent arithmetic: the libraries' switches (casa_core.numerics) and the
BLAS-free linear algebra (casa_core.fixed_order)."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from decimal import Decimal, localcontext

import numpy as np
import pytest

from casa_core import fixed_order, numerics
from casa_core.robot import kinematics as kin


def test_the_test_process_runs_every_library_at_the_baseline():
    # tests/conftest.py imports casa_core before numpy; a plugin that loaded numpy
    # first would show here.
    assert numerics.unpinned() == []


def test_pinning_keeps_what_the_environment_sets_and_never_touches_openblas():
    environ = {"OPENBLAS_CORETYPE": "Prescott", "ATEN_CPU_CAPABILITY": "default"}
    numerics.pin_environment(environ)
    assert environ["OPENBLAS_CORETYPE"] == "Prescott"
    assert environ["ATEN_CPU_CAPABILITY"] == "default"
    assert environ["NPY_DISABLE_CPU_FEATURES"] == numerics.SWITCHES["NPY_DISABLE_CPU_FEATURES"]
    assert not any(name.startswith("OPENBLAS") for name in numerics.SWITCHES)
    # numpy refuses both of its switches at once: a user's enable list wins.
    environ = {"NPY_ENABLE_CPU_FEATURES": "X86_V3"}
    numerics.pin_environment(environ)
    assert "NPY_DISABLE_CPU_FEATURES" not in environ


def test_fixed_order_matches_numpy_to_rounding():
    rng = np.random.default_rng(3)
    a, b, v = rng.normal(size=(6, 7)), rng.normal(size=(7, 4)), rng.normal(size=7)
    assert fixed_order.matmul(a, b) == pytest.approx(a @ b, rel=1e-13, abs=1e-14)
    assert fixed_order.matmul(a, v) == pytest.approx(a @ v, rel=1e-13, abs=1e-14)
    stack = rng.normal(size=(5, 4, 4))
    assert fixed_order.matmul(stack, stack) == pytest.approx(stack @ stack, rel=1e-12, abs=1e-14)
    assert fixed_order.dot(v, v) == pytest.approx(v @ v, rel=1e-14)
    assert fixed_order.length(v) == pytest.approx(np.linalg.norm(v), rel=1e-15)
    spd = a @ a.T + 0.1 * np.eye(6)
    rhs = rng.normal(size=6)
    assert fixed_order.solve_spd(spd, rhs) == pytest.approx(np.linalg.solve(spd, rhs), rel=1e-10)
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        fixed_order.solve_spd(-np.eye(3), np.ones(3))


def test_length_is_within_an_ulp_of_the_exact_length():
    # The reference: the exact square root of the exact sum of squares (50 digits).
    rng = np.random.default_rng(1)
    vectors = rng.normal(size=(2000, 3)) * rng.choice([1e-3, 0.1, 1.0, 10.0], size=(2000, 1))
    with localcontext() as context:
        context.prec = 50
        for v in vectors:
            exact = float(sum(Decimal(float(x)) ** 2 for x in v).sqrt())
            assert abs(fixed_order.length(v) - exact) <= math.ulp(exact)


_PROBE = """
import numpy as np
from casa_core import fixed_order
from casa_core.robot import kinematics as kin
rng = np.random.default_rng(5)
a, b = rng.normal(size=(6, 7)), rng.normal(size=(7, 7))
q = kin.inverse_kinematics([0.45, 0.1, 0.25], 0.3)
spd = fixed_order.matmul(a, a.T) + np.eye(6)
parts = [fixed_order.matmul(a, b), fixed_order.dot(a[0], b[0]), fixed_order.length(a[1]),
         fixed_order.solve_spd(spd, a[:, 0]), kin.link_frames(q), q]
print(b"".join(np.asarray(x, dtype=float).tobytes() for x in parts).hex())
"""


@pytest.mark.parametrize("kernel", ["Haswell", "Prescott"])
def test_the_bits_do_not_depend_on_the_openblas_kernel(kernel):
    # OpenBLAS picks its kernel by the CPU (here forced by its own switch); the
    # kinematics and the fixed-order algebra never call it, so the bits stay. (Built
    # with ``a @ a.T``, the probe differs under Prescott on an AVX-512 Xeon.)
    def probe(environ):
        run = subprocess.run(
            [sys.executable, "-c", _PROBE], env=environ, capture_output=True, text=True, check=True
        )
        return run.stdout

    default = {k: v for k, v in os.environ.items() if not k.startswith("OPENBLAS_CORETYPE")}
    assert probe(default | {"OPENBLAS_CORETYPE": kernel}) == probe(default)


def test_inverse_kinematics_still_reaches_the_pose():
    q = kin.inverse_kinematics([0.45, 0.1, 0.25], 0.3)
    pose = kin.forward_kinematics(q)
    assert pose[:3, 3] == pytest.approx([0.45, 0.1, 0.25], abs=1e-6)
    assert kin.rot_of(pose[:3, :3]) == pytest.approx(0.3, abs=1e-6)
