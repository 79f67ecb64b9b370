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
    flat: np.ndarray  # (E,) flat index into the band storage's transpose (2M, bandwidth + 1)
    at_diag: np.ndarray  # (2M,) position in E of each band variable's diagonal entry
    row6: np.ndarray  # (E,) row / column band variable 2 q + s as a column of the (3, 6 M)
    col6: np.ndarray  # derivative table: (1 + s) M + q
    bandwidth: int


# the four entries (s, t) of a 2x2 block: row 2 q + s, column 2 n + t
_S, _T = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])


@lru_cache(maxsize=32)
def band_layout(m: int, offsets: tuple[int, ...]) -> BandLayout:
    """Pure index tables (cached: windows of one hub share a few sizes). ``offsets`` increasing
    and starting with 0 (:meth:`OrientationProblem.gram_bands`). Built with few numpy calls:
    a first solve of a new size pays for it."""
    off = np.asarray(offsets)
    if off[0] != 0:
        raise ValueError(f"band_layout: offsets must start with 0, got {offsets}")
    q = np.arange(m)
    # interleaved numbering 0, M-1, 1, M-2, ...: cyclic neighbours end up <= 2 apart
    order = np.where(q % 2 == 0, q // 2, m - 1 - q // 2)
    pos = np.argsort(order)
    idx = pos[(order + off[:, None]) % m]  # (K, M)
    perm = (2 * order[:, None] + _S[::3]).reshape(-1)
    # candidate entries (k, q, s, t), K M 4 of them; the lower triangle is stored
    r = np.broadcast_to((2 * q)[:, None] + _S, (len(off), m, 4)).reshape(-1)
    n_e = np.broadcast_to(idx[:, :, None], (len(off), m, 4)).reshape(-1)
    c = 2 * n_e + np.tile(_T, len(off) * m)
    keep = np.flatnonzero(r >= c)
    r, c, n_e = r[keep], c[keep], n_e[keep]
    bandwidth = int((r - c).max())
    # offset 0 comes first: its kept entries are (A, A), (B, A), (B, B) of each position q,
    # E positions 3 q, 3 q + 1, 3 q + 2
    v = np.arange(2 * m)
    tables = [order, perm, np.argsort(perm), idx, r, c, keep // 4, c * (bandwidth + 1) + (r - c),
              3 * (v // 2) + 2 * (v % 2), (1 + r % 2) * m + r // 2, (1 + c % 2) * m + n_e]
    for a in tables:  # shared by every model of this size (cached): read-only
        a.setflags(write=False)
    return BandLayout(*tables, bandwidth)


class BandedAxisModel:
    """Axis-model objective, gradient and banded Hessian of one problem (built once), all in
    band numbering (see :class:`BandLayout`): x, gradients and diagonals are (2M,) band
    variables, curvature blocks (3, M) per band position."""

    def __init__(self, prob: OrientationProblem):
        offsets, Gk = prob.gram_bands  # Gk[k, i] = G[i, (i + offsets[k]) % M]
        m, n = prob.m, 2 * prob.m
        lay = band_layout(m, tuple(offsets.tolist()))
        self.m, self.n, self.layout = m, n, lay
        self.bandwidth = lay.bandwidth
        # component-major arrays (components x points: contiguous rows, few numpy calls)
        self.Gb = Gk[:, lay.order]  # (K, M) in band positions
        self.g2 = 2.0 * self.Gb.reshape(-1)[lay.gram]  # (E,) 2 G of each stored entry
        self.R_jc = np.ascontiguousarray(prob.R_HL[lay.order].transpose(2, 1, 0))  # (3, 3, M)
        # the table's signs folded into the frames: (6 r, 3 j, 3 c, M) = sign[r, j] R[j, c]
        self.R_signed = _SIGN[:, :, None, None] * self.R_jc
        # T: [0, sa, ca, sb, cb, sa cb, sa sb, ca cb, ca sb] x M
        self._T = T = np.zeros((9, m))
        self._T_sin, self._T_cos = T[1:5:2], T[2:5:2]  # (sa, sb), (ca, cb)
        self._T_products = T[5:9].reshape(2, 2, m)
        for view in (self._T_products, self._T_sin, self._T_cos):
            assert np.may_share_memory(view, T)
        # the band's free mask (transposed, C order): free[c] & free[c + d], from a zero-copy
        # sliding view of a padded copy of "free"
        self._free = np.ones(n + lay.bandwidth, bool)
        self._free_window = np.ndarray((n, lay.bandwidth + 1), bool, self._free, 0, (1, 1))

    def to_band(self, x: np.ndarray) -> np.ndarray:
        """(2M,) variables -> band variables."""
        return x[self.layout.perm]

    def from_band(self, xb: np.ndarray) -> np.ndarray:
        """(2M,) band variables -> variables."""
        return xb[self.layout.inv_perm]

    def _laplacian(self, A: np.ndarray) -> np.ndarray:
        """G @ A for A (3, M) (components x band positions)."""
        return np.einsum("km,ckm->cm", self.Gb, A.take(self.layout.idx, axis=1))

    def _table(self, xb: np.ndarray, rows: slice) -> np.ndarray:
        """(3, r, M) rows of [axis, d/dA, d/dB, d2/dA2, d2/dAdB, d2/dB2] in H (components
        first)."""
        T, xT = self._T, xb.reshape(self.m, 2).T
        np.sin(xT, out=self._T_sin)
        np.cos(xT, out=self._T_cos)
        # (sa, ca) x (cb, sb): rows 1, 2 times rows 4, 3
        np.multiply(T[1:3, None], T[None, 4:2:-1], out=self._T_products)
        L = T.take(_PICK[rows], axis=0)  # (r, 3 j, M): the unsigned trig products in L
        # sum_j sign[r, j] L[r, j] R[:, j], components first (c, r, M)
        return np.einsum("rjm,rjcm->crm", L, self.R_signed[rows])

    def objective(self, xb: np.ndarray) -> float:
        A = self._table(xb, slice(0, 1))[:, 0]
        return float(np.vdot(A, self._laplacian(A)))

    def derivatives(self, xb: np.ndarray):
        """f, gradient (2M,), Gauss-Newton entries of the stored band (E,), curvature blocks
        (3: aa, ab, bb, M) per band position."""
        W = self._table(xb, slice(None))  # (3 c, 6, M)
        A = W[:, 0]
        GA = self._laplacian(A)
        P = np.einsum("ckm,cm->km", W[:, 1:], GA + GA)  # (5, M): gradient (2), curvature (3)
        # d axis / d (band variable 2 q + s) is column (1 + s) M + q of Wc (a view)
        Wc = W.reshape(3, -1)
        hv = np.einsum("ce,ce->e", Wc.take(self.layout.row6, axis=1),
                       Wc.take(self.layout.col6, axis=1)) * self.g2
        return float(np.vdot(A, GA)), P[:2].T.reshape(-1), hv, P[2:]

    def gauss_newton_diagonal(self, hv: np.ndarray) -> np.ndarray:
        """(2M,) Gauss-Newton diagonal 2 G_mm |d axis / d theta|^2 (> 0)."""
        return hv[self.layout.at_diag]

    def hessian_band(self, hv: np.ndarray, curv: np.ndarray) -> np.ndarray:
        """The model Hessian (Gauss-Newton entries + curvature blocks ``curv``) in LAPACK lower
        band storage: (bandwidth + 1, 2M), Fortran order."""
        abT = np.zeros((self.n, self.bandwidth + 1))
        abT.flat[self.layout.flat] = hv
        ab = abT.T
        # the curvature blocks: (A, A), (B, B) on the diagonal (row 0), (B, A) in row 1
        ab[0, 0::2] += curv[0]
        ab[0, 1::2] += curv[2]
        ab[1, 0::2] += curv[1]
        return ab

    def hess_vec(self, abH: np.ndarray, v: np.ndarray, alpha: float = 1.0, beta: float = 0.0,
                 y: np.ndarray | None = None) -> np.ndarray:
        """alpha H @ v + beta y with H from :meth:`hessian_band` (BLAS ``dsbmv``,
        single-threaded; y is not modified)."""
        if y is None:
            return dsbmv(self.bandwidth, alpha, abH, v, lower=1)
        return dsbmv(self.bandwidth, alpha, abH, v, beta=beta, y=y, lower=1)

    def free_mask(self, fixed: np.ndarray) -> np.ndarray:
        """(bandwidth + 1, 2M) band mask (Fortran order, like the band): 1 where neither the
        row nor the column is fixed."""
        free = self._free[: self.n]
        np.logical_not(fixed, out=free)
        return np.logical_and(free[:, None], self._free_window).T

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
