"""Small linear algebra that adds in one fixed order on every CPU, off the BLAS.

numpy's ``@``, ``dot``, ``linalg.norm`` of a vector and ``linalg.solve`` call the BLAS
and LAPACK, whose kernel (and so the last bit of a result) OpenBLAS picks by the
processor. The functions here compute the same quantities with numpy's own loops
(``einsum`` without path optimisation, which never calls the BLAS), ``math.hypot`` and
a Cholesky written out, so the result-bearing arithmetic of a trial gives the same bits
on every machine (docs/reproducibility.md). They are meant for the small matrices of
kinematics and geometry: 3 x 3 to 7 x 7.
"""

from __future__ import annotations

import math

import numpy as np


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` for matrices (stacks broadcast) and matrix-vector products.

    Examples
    --------
    >>> matmul(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([1.0, 1.0]))
    array([3., 7.])
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if b.ndim == 1:
        return np.einsum("...ij,j->...i", a, b)
    return np.einsum("...ij,...jk->...ik", a, b)


def dot(a: np.ndarray, b: np.ndarray) -> float:
    """The inner product of two vectors.

    Examples
    --------
    >>> dot(np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0, 6.0]))
    32.0
    """
    return float(np.einsum("i,i->", np.asarray(a, dtype=float), np.asarray(b, dtype=float)))


def length(vector: np.ndarray) -> float:
    """Euclidean length of a vector: ``math.hypot`` of its entries (correctly rounded
    accumulation, independent of any kernel).

    Examples
    --------
    >>> length(np.array([0.3, 0.4, 0.0]))
    0.5
    """
    return math.hypot(*np.ravel(vector).tolist())


def solve_spd(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``x`` with ``matrix x = rhs`` for a symmetric positive definite ``matrix``, by
    Cholesky factorisation and two triangular solves.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``matrix`` is not positive definite.

    Examples
    --------
    >>> solve_spd(np.array([[4.0, 2.0], [2.0, 3.0]]), np.array([2.0, 1.0]))
    array([0.5, 0. ])
    """
    a = np.asarray(matrix, dtype=float).tolist()
    x = np.asarray(rhs, dtype=float).tolist()
    n = len(x)
    low = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for k in range(i + 1):
            total = a[i][k]
            for m in range(k):
                total -= low[i][m] * low[k][m]
            if i == k:
                if not total > 0.0:
                    raise np.linalg.LinAlgError("matrix is not positive definite")
                low[i][i] = math.sqrt(total)
            else:
                low[i][k] = total / low[k][k]
    for i in range(n):
        total = x[i]
        for m in range(i):
            total -= low[i][m] * x[m]
        x[i] = total / low[i][i]
    for i in range(n - 1, -1, -1):
        total = x[i]
        for m in range(i + 1, n):
            total -= low[m][i] * x[m]
        x[i] = total / low[i][i]
    return np.array(x)


__all__ = ["dot", "length", "matmul", "solve_spd"]
