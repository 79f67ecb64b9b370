"""The ``axis`` objective, gradient and banded Hessian for the exact solver, in band numbering.

The objective J = sum_ij G_ij axis_i . axis_j (G = C^T C, see
:meth:`~drakedeburr.orientation.models.OrientationProblem.gram_bands`) couples neighbouring CL
points only, so its Hessian is block-banded - cyclic for the closed loop. Numbering the points
0, M-1, 1, M-2, 2, ... ("band numbering") makes the cyclic band an ordinary band (lower
bandwidth 5 for first differences, 9 with second differences). :class:`BandedAxisModel` works
in that numbering throughout: the solver permutes x once on entry and once on exit, and every
Newton step is one LAPACK banded Cholesky solve on arrays already in band order.

Written for a low fixed cost per call (issue 19: the exact solve must stay >= 100x faster than
the PSO baseline also on a busy machine): index tables are built once per problem size, a
derivative evaluation is ~15 numpy calls on (M, 6, 3) arrays, the Gauss-Newton Hessian entries
are computed only for the stored lower band, and nothing calls a threaded BLAS routine
(OpenBLAS threads wait for a free core on a loaded machine: milliseconds per call).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.linalg.blas import dsbmv

from drakedeburr.frames.local_frames import axis_from_angles, axis_jacobian
from drakedeburr.orientation.models import OrientationProblem

__all__ = ["BandedAxisModel", "band_layout"]


# The per-point table [axis, d/dA, d/dB, d2/dA2, d2/dAdB, d2/dB2] (6, 3) in L is evaluated as
# signed picks from T = [0, sa, ca, sb, cb, sa cb, sa sb, ca cb, ca sb] (one sin and one cos
# call fill columns 1-4, one multiply the products; then one gather, no per-entry formulas).
# The picks and signs are NOT written by hand: they are derived here, once at import, from the
# single definition of the convention in drakedeburr.frames.local_frames (axis_from_angles,
# axis_jacobian; the second derivatives by central differences of axis_jacobian). A hand-written
# copy of the old theta_A sign once made this solver optimise a different problem than the one
# it reported on.
def _trig_products(a: float, b: float) -> np.ndarray:
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    return np.concatenate([[0.0, sa, ca, sb, cb], np.outer([sa, ca], [cb, sb]).reshape(-1)])


def _derive_tables() -> tuple[np.ndarray, np.ndarray]:
    """(_PICK, _SIGN), both (6, 3), matching local_frames at generic angles; raises if the
    convention there is not a signed pick of the trig products."""
    h = 1e-5
    samples = [(0.37, 0.23), (-0.81, 0.57), (1.13, -0.44)]
    rows = []  # per sample: (6, 3) table
    for a, b in samples:
        J = axis_jacobian(a, b)  # (3, 2)
        d_a = (axis_jacobian(a + h, b) - axis_jacobian(a - h, b)) / (2 * h)
        d_b = (axis_jacobian(a, b + h) - axis_jacobian(a, b - h)) / (2 * h)
        rows.append(np.stack([axis_from_angles(a, b), J[:, 0], J[:, 1], d_a[:, 0],
                              0.5 * (d_a[:, 1] + d_b[:, 0]), d_b[:, 1]]))
    T = np.stack([_trig_products(a, b) for a, b in samples])  # (S, 9)
    pick, sign = np.zeros((6, 3), int), np.zeros((6, 3))
    for r in range(6):
        for c in range(3):
            v = np.array([tab[r, c] for tab in rows])
            for p in range(T.shape[1]):
                for s_ in (1.0, -1.0):
                    if np.abs(s_ * T[:, p] - v).max() < 1e-7:
                        pick[r, c], sign[r, c] = p, (0.0 if p == 0 else s_)
                        break
                else:
                    continue
                break
            else:
                raise RuntimeError("local_frames.axis_from_angles is not a signed product of "
                                   "sin/cos of theta_A, theta_B: banded.py's tables need work")
    return pick, sign


_PICK, _SIGN = _derive_tables()
# the same picks from [T, -T[1:]] (17 columns, no multiply by the signs)
_SIGNED_PICK = np.where(_SIGN < 0, _PICK + 8, _PICK)


@dataclass(frozen=True)
class BandLayout:
    """Index tables of the banded Hessian for M points coupled at the given cyclic offsets.

    Band numbering: band position q holds point ``order[q]``; band variable 2 q + s is angle s
    (0: theta_A, 1: theta_B) of that point. The Hessian's stored entries are its lower band
    (row >= column), E of them, in LAPACK lower band storage (bandwidth + 1, 2M).
    """

    order: np.ndarray  # (M,) band position -> point
    perm: np.ndarray  # (2M,) band variable -> variable (x_band = x[perm])
    inv_perm: np.ndarray  # (2M,) variable -> band variable (x = x_band[inv_perm])
    idx: np.ndarray  # (K, M) band position of the neighbour at offset k of band position q
    row: np.ndarray  # (E,) band variable (row) of each stored entry
    col: np.ndarray  # (E,) band variable (column)
    gram: np.ndarray  # (E,) flat index into Gk (K, M) (in band positions) of its coupling
    flat: np.ndarray  # (E,) flat index into the band storage
    at_diag: np.ndarray  # (2M,) position in E of each band variable's diagonal entry
    band_row: np.ndarray  # (bandwidth + 1, 2M) row of each band storage slot (clipped)
    band_col: np.ndarray  # (bandwidth + 1, 2M) column of each band storage slot
    bandwidth: int


@lru_cache(maxsize=32)
def band_layout(m: int, offsets: tuple[int, ...]) -> BandLayout:
    """Pure index tables (cached: windows of one hub share a few sizes; ~50 us to build)."""
    off = np.asarray(offsets)
    # interleaved numbering 0, M-1, 1, M-2, ...: cyclic neighbours end up <= 2 apart
    order = np.empty(m, int)
    order[0::2] = np.arange((m + 1) // 2)
    order[1::2] = m - 1 - np.arange(m // 2)
    pos = np.empty(m, int)
    pos[order] = np.arange(m)
    idx = pos[(order[None, :] + off[:, None]) % m]  # (K, M)
    n = 2 * m
    perm = (2 * order[:, None] + np.arange(2)).reshape(-1)
    q = np.tile(np.arange(m), len(off))  # coupling p = k M + q: (q, idx[k, q])
    s, t = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])
    r = ((2 * q)[:, None] + s).reshape(-1)
    c = ((2 * idx.reshape(-1))[:, None] + t).reshape(-1)
    keep = np.flatnonzero(r >= c)  # lower triangle
    where = np.full(len(r), -1)
    where[keep] = np.arange(len(keep))
    r, c = r[keep], c[keep]
    bandwidth = int((r - c).max())
    flat = (r - c) * n + c
    k0 = int(np.flatnonzero(off == 0)[0])
    base = 4 * (k0 * m + np.arange(m))  # the diagonal 2x2 block of each band position
    at_diag = np.stack([where[base], where[base + 3]], 1).reshape(-1)  # (A, A), (B, B)
    band_col = np.broadcast_to(np.arange(n), (bandwidth + 1, n))
    band_row = np.minimum(band_col + np.arange(bandwidth + 1)[:, None], n - 1)
    return BandLayout(order, perm, np.argsort(perm), idx, r, c, keep // 4, flat, at_diag,
                      band_row, np.ascontiguousarray(band_col), bandwidth)


class BandedAxisModel:
    """Axis-model objective, gradient and banded Hessian of one problem (built once), all in
    band numbering (see :class:`BandLayout`): x, gradients and diagonals are (2M,) band
    variables, curvature blocks (M, 3) per band position."""

    def __init__(self, prob: OrientationProblem):
        offsets, Gk = prob.gram_bands  # Gk[k, i] = G[i, (i + offsets[k]) % M]
        m = prob.m
        lay = band_layout(m, tuple(offsets.tolist()))
        self.m, self.n, self.layout = m, 2 * m, lay
        self.bandwidth = lay.bandwidth
        self.Gb = Gk[:, lay.order]  # (K, M) in band positions
        self.Gb3 = self.Gb[:, :, None]
        self.g2 = 2.0 * self.Gb.reshape(-1)[lay.gram]  # (E,) 2 G of each stored entry
        self.R_t = np.ascontiguousarray(prob.R_HL[lay.order].transpose(0, 2, 1))  # (M, 3, 3)
        # [0, sa, ca, sb, cb, sa cb, sa sb, ca cb, ca sb, the same 8 negated]; column 0 stays 0
        self._T = np.zeros((m, 17))
        self._T_products = self._T[:, 5:9].reshape(m, 2, 2)  # views into _T (checked)
        self._T_sin, self._T_cos = self._T[:, 1:5:2], self._T[:, 2:5:2]
        for view in (self._T_products, self._T_sin, self._T_cos):
            assert np.shares_memory(view, self._T)
        # rows of d axis / d (band variable 2 q + s) in the (M * 6, 3) table: 6 q + 1 + s
        self.row6 = 6 * (lay.row // 2) + 1 + lay.row % 2
        self.col6 = 6 * (lay.col // 2) + 1 + lay.col % 2

    def to_band(self, x: np.ndarray) -> np.ndarray:
        """(2M,) variables -> band variables."""
        return x[self.layout.perm]

    def from_band(self, xb: np.ndarray) -> np.ndarray:
        """(2M,) band variables -> variables."""
        return xb[self.layout.inv_perm]

    def _laplacian(self, A: np.ndarray) -> np.ndarray:
        """G @ A for A (M, 3) in band positions."""
        return (self.Gb3 * np.take(A, self.layout.idx, axis=0)).sum(0)

    def _table(self, xb: np.ndarray, rows: slice) -> np.ndarray:
        """(M, r, 3) rows of [axis, d/dA, d/dB, d2/dA2, d2/dAdB, d2/dB2] in H."""
        T, xb2 = self._T, xb.reshape(self.m, 2)
        np.sin(xb2, out=self._T_sin)  # (sa, sb) -> columns 1, 3
        np.cos(xb2, out=self._T_cos)  # (ca, cb) -> columns 2, 4
        # (sa, ca) x (cb, sb): columns 1, 2 times columns 4, 3
        np.multiply(T[:, 1:3, None], T[:, None, 4:2:-1], out=self._T_products)
        np.negative(T[:, 1:9], out=T[:, 9:])
        return np.matmul(np.take(T, _SIGNED_PICK[rows], axis=1), self.R_t)

    def objective(self, xb: np.ndarray) -> float:
        A = self._table(xb, slice(0, 1))[:, 0, :]
        return float(np.vdot(A, self._laplacian(A)))

    def derivatives(self, xb: np.ndarray):
        """f, gradient (2M,), Gauss-Newton entries of the stored band (E,), curvature blocks
        (M, 3: aa, ab, bb) per band position."""
        W = self._table(xb, slice(None))  # (M, 6, 3)
        A = W[:, 0, :]
        GA = self._laplacian(A)
        P = np.einsum("mc,mkc->mk", GA + GA, W[:, 1:, :])
        W6 = W.reshape(-1, 3)
        # np.take: a third of the cost of fancy indexing for row gathers
        a, b = np.take(W6, self.row6, axis=0), np.take(W6, self.col6, axis=0)
        hv = np.einsum("ec,ec->e", a, b) * self.g2
        return float(np.vdot(A, GA)), P[:, :2].reshape(-1), hv, P[:, 2:]

    def gauss_newton_diagonal(self, hv: np.ndarray) -> np.ndarray:
        """(2M,) Gauss-Newton diagonal 2 G_mm |d axis / d theta|^2 (> 0)."""
        return hv[self.layout.at_diag]

    def hessian_band(self, hv: np.ndarray, curv: np.ndarray) -> np.ndarray:
        """The model Hessian (Gauss-Newton entries + curvature blocks ``curv``) in LAPACK lower
        band storage: (bandwidth + 1, 2M)."""
        ab = np.zeros((self.bandwidth + 1, self.n))
        ab.flat[self.layout.flat] = hv
        # the curvature blocks: (A, A), (B, B) on the diagonal (row 0), (B, A) in row 1
        ab[0, 0::2] += curv[:, 0]
        ab[0, 1::2] += curv[:, 2]
        ab[1, 0::2] += curv[:, 1]
        return ab

    def hess_vec(self, abH: np.ndarray, v: np.ndarray) -> np.ndarray:
        """H @ v with H from :meth:`hessian_band` (BLAS ``dsbmv``, single-threaded)."""
        return dsbmv(self.bandwidth, 1.0, abH, v, lower=1)

    def free_mask(self, fixed: np.ndarray) -> np.ndarray:
        """(bandwidth + 1, 2M) band mask: 1 where neither row nor column is fixed."""
        free = ~fixed
        return np.take(free, self.layout.band_row) & np.take(free, self.layout.band_col)

    def system(self, abH, mask, damp, fixed, ab) -> None:
        """Fill ab with H + damp I, fixed rows and columns -> identity (``mask`` from
        :meth:`free_mask`, None when nothing is fixed)."""
        if mask is None:
            ab[...] = abH
        else:
            np.multiply(abH, mask, out=ab)
        ab[0] += damp
        if mask is not None:
            ab[0, fixed] = 1.0
