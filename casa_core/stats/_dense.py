"""Dense linear algebra of the mixed model in one fixed order of operations, off the BLAS.

numpy's ``@``, ``inv``, ``solve`` and ``slogdet`` call OpenBLAS and LAPACK, whose kernel
(and so the last bits) depends on the processor; an optimiser turns last bits into a
different optimum in the sixth digit. These compiled loops (no ``fastmath``: no
reordering, no fused multiply-adds) give the same bits on every machine, and the mixed
model's matrices (tens of observations) are small enough for them.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def _matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    n, m = a.shape
    k = b.shape[1]
    out = np.zeros((n, k))
    for i in range(n):
        for j in range(m):
            aij = a[i, j]
            for c in range(k):
                out[i, c] += aij * b[j, c]
    return out


@numba.njit(cache=True)
def _cholesky(a: np.ndarray) -> tuple[np.ndarray, bool]:
    """Lower ``L`` with ``a = L L'``, and False if ``a`` is not positive definite."""
    n = a.shape[0]
    low = np.zeros((n, n))
    for i in range(n):
        for k in range(i + 1):
            total = a[i, k]
            for m in range(k):
                total -= low[i, m] * low[k, m]
            if i == k:
                if not total > 0.0:
                    return low, False
                low[i, i] = math.sqrt(total)
            else:
                low[i, k] = total / low[k, k]
    return low, True


@numba.njit(cache=True)
def _cholesky_solve(low: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``L L' x = b`` for each column of ``b``."""
    n, k = b.shape
    x = b.copy()
    for c in range(k):
        for i in range(n):
            total = x[i, c]
            for m in range(i):
                total -= low[i, m] * x[m, c]
            x[i, c] = total / low[i, i]
        for i in range(n - 1, -1, -1):
            total = x[i, c]
            for m in range(i + 1, n):
                total -= low[m, i] * x[m, c]
            x[i, c] = total / low[i, i]
    return x


def matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` for matrices and matrix-vector products, in the compiled loops.

    Examples
    --------
    >>> matmul(np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([[0.0, 1.0], [1.0, 0.0]]))
    array([[2., 1.],
           [4., 3.]])
    """
    a, b = np.ascontiguousarray(a, dtype=float), np.asarray(b, dtype=float)
    if b.ndim == 1:
        return _matmul(a, np.ascontiguousarray(b[:, None]))[:, 0]
    return _matmul(a, np.ascontiguousarray(b))


def cholesky(a: np.ndarray) -> np.ndarray:
    """The lower Cholesky factor of a symmetric positive definite matrix.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``a`` is not positive definite.

    Examples
    --------
    >>> cholesky(np.array([[4.0, 2.0], [2.0, 5.0]]))
    array([[2., 0.],
           [1., 2.]])
    """
    low, ok = _cholesky(np.ascontiguousarray(a, dtype=float))
    if not ok:
        raise np.linalg.LinAlgError("matrix is not positive definite")
    return low


def cholesky_solve(low: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``x`` with ``L L' x = b`` given ``L`` from :func:`cholesky` (``b`` a vector or matrix).

    Examples
    --------
    >>> low = cholesky(np.array([[4.0, 2.0], [2.0, 5.0]]))
    >>> cholesky_solve(low, np.array([6.0, 7.0]))
    array([1., 1.])
    """
    b = np.asarray(b, dtype=float)
    column = b.ndim == 1
    x = _cholesky_solve(low, np.ascontiguousarray(b[:, None] if column else b))
    return x[:, 0] if column else x


def logdet(low: np.ndarray) -> float:
    """``log det(L L')`` from the Cholesky factor.

    Examples
    --------
    >>> round(logdet(cholesky(np.array([[4.0, 2.0], [2.0, 5.0]]))), 6)  # log 16
    2.772589
    """
    return float(2.0 * np.sum(np.log(np.diagonal(low))))


def spd_inverse(a: np.ndarray) -> np.ndarray:
    """The inverse of a symmetric positive definite matrix (by :func:`cholesky`).

    Examples
    --------
    >>> spd_inverse(np.array([[4.0, 2.0], [2.0, 5.0]])) * 16
    array([[ 5., -2.],
           [-2.,  4.]])
    """
    a = np.asarray(a, dtype=float)
    return cholesky_solve(cholesky(a), np.eye(a.shape[0]))


__all__ = ["cholesky", "cholesky_solve", "logdet", "matmul", "spd_inverse"]
