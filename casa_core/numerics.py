"""The arithmetic results are computed with: the same on every x86-64 CPU at x86-64-v3 or above.

numpy, torch (its ATen kernels, MKL and oneDNN) and numba choose their SIMD code paths
when they load, by the CPU they find: AVX-512 on many Intel processors, AVX2 on AMD
ones. Wider paths sum in another order, so a last bit differs, and a closed loop turns
a last bit into another key press. Each library's own switch caps it at the baseline,
x86-64-v3 (AVX2 and FMA: Intel from Haswell, 2013; AMD from Excavator/Zen), which every
machine at or above it then runs identically. The switches are read when the library
loads, so :mod:`casa_core` imports this module before anything else, and a switch the
environment already sets is left as it is.

OpenBLAS is not switched: ``OPENBLAS_CORETYPE`` is what some machines set to avoid
kernels that crash or compute wrongly on their processors, and the kernel it selects
changes the last bit of every BLAS call. Result-bearing arithmetic therefore stays off
the BLAS (elementwise products summed in a fixed order, ``math.hypot``, compiled loops):
see docs/reproducibility.md.

MKL's vector maths (VML), where torch sends sin, cos, exp, sqrt and other elementwise
functions of a CPU tensor, picks its code path by processor vendor whatever ``MKL_CBWR``
says; :mod:`casa_core.portable_math` computes the ones casa uses with numpy instead.
"""

from __future__ import annotations

import os
import sys

#: The baseline every switch caps the libraries at.
BASELINE = "x86-64-v3"
#: Each library's switch and its value at :data:`BASELINE`.
SWITCHES = {
    # numpy: its dispatch targets above x86-64-v3 (numpy 2.4: X86_V4, AVX512_ICL, _SPR).
    "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
    # torch: ATen's vectorised kernels (reductions, elementwise maths).
    "ATEN_CPU_CAPABILITY": "avx2",
    # MKL (any matrix product left in torch; the learned cost's run in a fixed order):
    # the code path Intel documents as giving the same results on Intel and non-Intel
    # processors (conditional numerical reproducibility).
    "MKL_CBWR": "COMPATIBLE",
    # oneDNN (some of torch's CPU operators).
    "ONEDNN_MAX_CPU_ISA": "AVX2",
    # numba: compile for the baseline CPU, not the host (also makes its cache portable).
    "NUMBA_CPU_NAME": "haswell",
}


def pin_environment(environ=os.environ) -> None:
    """Set every switch of :data:`SWITCHES` that ``environ`` does not set already.

    ``NPY_ENABLE_CPU_FEATURES`` and ``NPY_DISABLE_CPU_FEATURES`` cannot both be set
    (numpy refuses to load): where a user enables features, numpy's switch is left out.
    """
    for name, value in SWITCHES.items():
        if name == "NPY_DISABLE_CPU_FEATURES" and "NPY_ENABLE_CPU_FEATURES" in environ:
            continue
        environ.setdefault(name, value)


def unpinned() -> list[str]:
    """What in this process runs wider than :data:`BASELINE`: one line per library.

    Empty when every loaded library is capped. A library loaded before :mod:`casa_core`
    (for instance by a program that imports numpy first) is named with the reason.

    Examples
    --------
    >>> unpinned()
    []
    """
    problems = []
    if "numpy" in sys.modules:
        # Read from the loaded module: this one imports nothing but os and sys.
        features = sys.modules["numpy"]._core._multiarray_umath.__cpu_features__
        wide = [f for f in SWITCHES["NPY_DISABLE_CPU_FEATURES"].split() if features.get(f)]
        if wide:
            problems.append(f"numpy dispatches to {', '.join(wide)} (imported before casa_core?)")
    if "torch" in sys.modules:
        capability = sys.modules["torch"].backends.cpu.get_cpu_capability()
        if capability not in ("AVX2", "DEFAULT"):
            problems.append(f"torch's ATen runs {capability} kernels (imported before casa_core?)")
    for name, value in SWITCHES.items():
        if os.environ.get(name) != value and not _user_choice(name):
            problems.append(f"{name} is {os.environ.get(name)!r}, not {value!r}")
    return problems


def _user_choice(name: str) -> bool:
    """numpy's switch left out because the user enables features instead."""
    return name == "NPY_DISABLE_CPU_FEATURES" and "NPY_ENABLE_CPU_FEATURES" in os.environ


__all__ = ["BASELINE", "SWITCHES", "pin_environment", "unpinned"]
