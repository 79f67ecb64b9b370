"""Tool-orientation models: the source's eq. 11 (``paper``) and the world-axis model (``axis``).

Decision variables, for a window with M CL points: theta = (theta_A, theta_B) per point [rad],
stacked as x = [theta_A_0, theta_B_0, theta_A_1, theta_B_1, ...] (2M,), each inside the box
[theta_min, theta_max] of the window class (config.ProcessParameters.bounds_large/small).
The tool axis at point i is ``zT_H_i = R_HL_i @ axis_from_angles(theta_A_i, theta_B_i)``
(see :mod:`drakedeburr.frames.local_frames`).

``paper`` (eq. 11, literal, open sequence i = 2..n as printed)::

    J = sum_i sqrt(W1 (d theta_A_i / d_i)^2 + W2 (d theta_B_i / d_i)^2)     [rad/m]

Degeneracy: every *constant* pair (theta_A, theta_B) inside the box has J = 0, the global
minimum. The model therefore fixes nothing: the angles are measured in the local frame, which
itself rotates along the edge, so a constant pair still swings the real tool axis wherever the
edge turns. The source's PSO "converging to near 0" is this degeneracy. Kept to reproduce the
source only.

``axis`` (the default): the change of the tool axis in the hub frame per unit path length,
i.e. a discretisation of the bending energy of the axis along the closed edge::

    J = sum_k |axis_{k+1} - axis_k|^2 / d_k                                  [1/m]
      + w2 * sum_i |(axis_{i+1} - axis_i)/d_i - (axis_i - axis_{i-1})/d_{i-1}|^2 / dbar_i

with d_k the chord between consecutive CL points (closed loop: the last point connects to the
first), dbar_i = (d_{i-1} + d_i)/2 and w2 [m^2] an optional second-difference weight (default 0).
The hub is rigid, so the change is the same in the world frame W and in H. For small turns
|axis_{k+1} - axis_k| is the turning angle, so J ~ integral of (d angle/ds)^2 ds: what the
robot's wrist feels. Both sums are sums of squares of residuals r(x); the exact solver uses
this (Gauss-Newton Hessian, banded projected Newton).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from drakedeburr.config import OrientationBounds
from drakedeburr.errors import InputError
from drakedeburr.frames.local_frames import axis_from_angles, axis_jacobian

__all__ = ["ModelName", "OrientationProblem", "make_problem"]

ModelName = Literal["axis", "paper"]


@dataclass(frozen=True, eq=False)
class OrientationProblem:
    """One window's orientation problem.

    Attributes:
        model: "axis" or "paper".
        p_HC: (M, 3) CL points in H [m].
        R_HL: (M, 3, 3) right-handed local frames [N_new, T, -B] in H.
        theta_min, theta_max: box bounds on both angles [rad].
        w1, w2: eq. 11 weights (paper model).
        second_difference_weight: w2 of the axis model [m^2] (0 = first differences only).
        closed: whether the last point connects to the first (axis model: True for window
            loops; paper model: False, as eq. 11 sums i = 2..n).
        name: for messages ("window 3").
    """

    model: ModelName
    p_HC: np.ndarray
    R_HL: np.ndarray
    theta_min: float
    theta_max: float
    w1: float = 0.6
    w2: float = 0.4
    second_difference_weight: float = 0.0
    closed: bool = True
    name: str = ""

    @property
    def m(self) -> int:
        return len(self.p_HC)

    @property
    def n_vars(self) -> int:
        return 2 * self.m

    @property
    def lower(self) -> np.ndarray:
        return np.full(self.n_vars, self.theta_min)

    @property
    def upper(self) -> np.ndarray:
        return np.full(self.n_vars, self.theta_max)

    @cached_property
    def segment_index(self) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) point indices of the segments (consecutive pairs); read-only, computed once."""
        i = np.arange(self.m if self.closed else self.m - 1)
        return _read_only(i), _read_only((i + 1) % self.m)

    @cached_property
    def chords(self) -> np.ndarray:
        """(K,) chord length d_k of each segment [m]; read-only, computed once."""
        i, j = self.segment_index
        return _read_only(np.linalg.norm(self.p_HC[j] - self.p_HC[i], axis=1))

    def axes(self, x: np.ndarray) -> np.ndarray:
        """Tool axes in H: (..., M, 3) for x (..., 2M)."""
        x = np.asarray(x, float)
        th = x.reshape(*x.shape[:-1], self.m, 2)
        a_L = axis_from_angles(th[..., 0], th[..., 1])
        return np.einsum("mij,...mj->...mi", self.R_HL, a_L)

    # -- objective -------------------------------------------------------------------------
    def objective(self, x: np.ndarray) -> np.ndarray:
        """Objective value(s): x (..., 2M) -> (...)."""
        x = np.asarray(x, float)
        if self.model == "paper":
            th = x.reshape(*x.shape[:-1], self.m, 2)
            i, j = self.segment_index
            d = self.chords
            da = (th[..., j, 0] - th[..., i, 0]) / d
            db = (th[..., j, 1] - th[..., i, 1]) / d
            return np.sqrt(self.w1 * da**2 + self.w2 * db**2).sum(axis=-1)
        r = self.residuals(x)
        return (r**2).sum(axis=(-1, -2))

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Axis model residuals (..., R, 3) with objective = sum of squares."""
        if self.model != "axis":
            raise ValueError("residuals exist for the axis model only")
        a = self.axes(x)
        i, j = self.segment_index
        d = self.chords
        diff = a[..., j, :] - a[..., i, :]
        r1 = diff / np.sqrt(d)[:, None]
        if self.second_difference_weight <= 0.0:
            return r1
        r2 = self._second(diff / d[:, None])
        return np.concatenate([r1, r2], axis=-2)

    def _second_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(segment before, segment after, scale) for each second-difference residual."""
        k = len(self.chords)
        d = self.chords
        if self.closed:
            after = np.arange(k)
            before = (after - 1) % k
        else:
            after = np.arange(1, k)
            before = after - 1
        dbar = 0.5 * (d[before] + d[after])
        return before, after, np.sqrt(self.second_difference_weight / dbar)

    def _second(self, slope: np.ndarray) -> np.ndarray:
        before, after, scale = self._second_rows()
        return (slope[..., after, :] - slope[..., before, :]) * scale[:, None]

    @cached_property
    def _gram(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """G = C^T C (M, M) and its nonzero pattern (i, j, G_ij)."""
        cols, vals = self.coefficient_rows()
        m = self.m
        # sum of the rows' outer products, accumulated without BLAS (a dense C^T C product
        # starts OpenBLAS threads: milliseconds, and far more on a busy machine)
        a = np.broadcast_to(cols[:, :, None], (*cols.shape, cols.shape[1]))
        b = np.broadcast_to(cols[:, None, :], a.shape)
        G = np.bincount((a * m + b).reshape(-1), (vals[:, :, None] * vals[:, None, :]).reshape(-1),
                        minlength=m * m).reshape(m, m)
        ii, jj = np.nonzero(np.abs(G) > 0)
        return G, ii, jj, G[ii, jj]

    @cached_property
    def gram_bands(self) -> tuple[np.ndarray, np.ndarray]:
        """The cyclic bands of G = C^T C: (offsets (K,), Gk (K, M)) with
        Gk[k, i] = G[i, (i + offsets[k]) % M]; offsets increasing in [0, M), those of the
        coupling pattern (consecutive points, and next-but-one with second differences).
        O(M), no dense (M, M) matrix."""
        if self.closed and self.second_difference_weight <= 0.0 and self.m >= 3:
            # the common case in closed form (the same sums as the general path below:
            # G_ii = w_(i-1)^2 + w_i^2, G_i,i+1 = -w_i^2, w = 1 / sqrt(d))
            w = 1.0 / np.sqrt(self.chords)
            w2 = w * w
            w2_prev = np.roll(w2, 1)
            return np.array([0, 1, self.m - 1]), np.stack([w2_prev + w2, -w2, -w2_prev])
        return self._gram_bands_general()

    def _gram_bands_general(self) -> tuple[np.ndarray, np.ndarray]:
        cols, vals = self.coefficient_rows()
        m, width = self.m, cols.shape[1]
        a = np.repeat(cols, width, axis=1).reshape(-1)  # row entry l, then l' = 0..L-1
        off = (np.tile(cols, (1, width)).reshape(-1) - a) % m
        v = (np.repeat(vals, width, axis=1) * np.tile(vals, (1, width))).reshape(-1)
        offsets = np.flatnonzero(np.bincount(off, minlength=m))
        lookup = np.zeros(m, int)
        lookup[offsets] = np.arange(len(offsets))
        Gk = np.bincount(lookup[off] * m + a, v, minlength=len(offsets) * m)
        return offsets, Gk.reshape(len(offsets), m)

    def coefficient_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """The rows of C (see :meth:`coefficients`) in sparse form: column indices (R, L) and
        values (R, L), L = 2 (first differences) or 4 (with second differences; first-difference
        rows padded with their own columns and zero values); a column may repeat within a row
        (the values add)."""
        i, j = self.segment_index
        d = self.chords
        w = 1.0 / np.sqrt(d)
        cols, vals = np.stack([j, i], 1), np.stack([w, -w], 1)
        if self.second_difference_weight <= 0.0:
            return cols, vals
        before, after, scale = self._second_rows()
        # (S[after] - S[before]) * scale with S = D / d, D @ axes = a_j - a_i
        cols2 = np.stack([j[after], i[after], j[before], i[before]], 1)
        inv_a, inv_b = 1.0 / d[after], 1.0 / d[before]
        vals2 = np.stack([inv_a, -inv_a, -inv_b, inv_b], 1) * scale[:, None]
        return (np.concatenate([np.concatenate([cols, cols], 1), cols2]),
                np.concatenate([np.concatenate([vals, np.zeros_like(vals)], 1), vals2]))

    def coefficients(self) -> np.ndarray:
        """(R, M) matrix C with residuals = C @ axes (every axis-model residual is a linear
        combination of the tool axes; row order as :meth:`residuals`)."""
        cols, vals = self.coefficient_rows()
        C = np.zeros((len(cols), self.m))
        np.add.at(C, (np.arange(len(cols))[:, None], cols), vals)
        return C

    def _point_derivatives(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """axes (M, 3), d axis / d theta (M, 3, 2) and second derivatives (M, 3, 2, 2) in H."""
        th = np.asarray(x, float).reshape(self.m, 2)
        a, b = th[:, 0], th[:, 1]
        sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
        z = np.zeros_like(a)
        # second derivatives of axis_from_angles = (-sin a cos b, -sin b, cos a cos b)
        d_aa = np.stack([sa * cb, z, -ca * cb], axis=-1)
        d_ab = np.stack([ca * sb, z, sa * sb], axis=-1)
        d_bb = np.stack([sa * cb, sb, -ca * cb], axis=-1)
        H_L = np.stack([np.stack([d_aa, d_ab], -1), np.stack([d_ab, d_bb], -1)], -1)
        R = self.R_HL
        axes_H = np.einsum("mij,mj->mi", R, axis_from_angles(a, b))
        J_H = np.einsum("mij,mjk->mik", R, axis_jacobian(a, b))
        H_H = np.einsum("mij,mjkl->mikl", R, H_L)
        return axes_H, J_H, H_H

    def residual_jacobian(self, x: np.ndarray) -> np.ndarray:
        """Dense Jacobian d r / d x, shape (3R, 2M), rows ordered as residuals(x).reshape(-1)."""
        _, J_pt, _ = self._point_derivatives(x)
        C = self.coefficients()
        # r[q, c] = sum_m C[q, m] a[m, c]  ->  d r[q, c] / d theta[m, s] = C[q, m] J_pt[m, c, s]
        return np.einsum("qm,mcs->qcms", C, J_pt).reshape(-1, self.n_vars)

    def derivatives(self, x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """Axis model derivatives.

        Returns:
            (objective, gradient (2M,), Gauss-Newton Hessian 2 J^T J (2M, 2M), curvature
            blocks (M, 2, 2)); the exact Hessian is the Gauss-Newton Hessian plus the blocks on
            its 2x2 diagonal (the curvature of each axis in its own two angles).
        """
        A, J_pt, H_pt = self._point_derivatives(x)
        G, ii, jj, g = self._gram  # G = C^T C is banded: use its nonzero pattern only
        GA = np.zeros_like(A)
        np.add.at(GA, ii, g[:, None] * A[jj])
        f = float(np.einsum("mc,mc->", A, GA))
        grad = 2.0 * np.einsum("mcs,mc->ms", J_pt, GA).reshape(-1)
        pair = 2.0 * g[:, None, None] * np.einsum("pcs,pct->pst", J_pt[ii], J_pt[jj])
        H_gn = np.zeros((self.m, 2, self.m, 2))
        H_gn[ii, :, jj, :] = pair
        H_gn = H_gn.reshape(self.n_vars, self.n_vars)
        blocks = 2.0 * np.einsum("mc,mcst->mst", GA, H_pt)
        return f, grad, H_gn, blocks

    def hessian(self, x: np.ndarray) -> np.ndarray:
        """Exact Hessian of the axis objective, (2M, 2M)."""
        _, _, H, blocks = self.derivatives(x)
        return H + block_diag_2(blocks)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """Exact gradient of the axis objective, (2M,)."""
        return self.derivatives(x)[1]

    def in_bounds(self, x: np.ndarray, tol: float = 1e-9) -> np.ndarray:
        """(M,) bool: both angles of point i inside the box (with tolerance)."""
        th = np.asarray(x, float).reshape(self.m, 2)
        return np.all((th >= self.theta_min - tol) & (th <= self.theta_max + tol), axis=1)


def make_problem(
    model: ModelName,
    p_HC: np.ndarray,
    R_HL: np.ndarray,
    bounds: OrientationBounds,
    *,
    w1: float = 0.6,
    w2: float = 0.4,
    second_difference_weight: float = 0.0,
    name: str = "",
) -> OrientationProblem:
    """Validate and build an :class:`OrientationProblem` (closed for axis, open for paper) with
    the box ``bounds`` (theta_min, theta_max) on both angles [rad]."""
    theta_min, theta_max = bounds.theta_min, bounds.theta_max
    if model not in ("axis", "paper"):
        raise InputError(f"{name}: unknown orientation model {model!r}; use 'axis' or 'paper'")
    p = np.asarray(p_HC, float)
    R = np.asarray(R_HL, float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 3:
        raise InputError(f"{name}: p_HC must be (M>=3, 3), got {p.shape}")
    if R.shape != (len(p), 3, 3):
        raise InputError(f"{name}: R_HL must be ({len(p)}, 3, 3), got {R.shape}")
    if not theta_min < theta_max:
        raise InputError(f"{name}: bounds need theta_min < theta_max, got {theta_min}, {theta_max}")
    if abs(w1 + w2 - 1.0) > 1e-9 or w1 < 0 or w2 < 0:
        raise InputError(f"{name}: eq. 11 needs W1 + W2 = 1, W1, W2 >= 0; got {w1}, {w2}")
    prob = OrientationProblem(model, p, R, float(theta_min), float(theta_max), float(w1),
                              float(w2), float(second_difference_weight),
                              closed=(model == "axis"), name=name)
    d = prob.chords
    bad = np.flatnonzero(d <= 1e-9)
    if bad.size:
        raise InputError(f"{name}: coincident consecutive CL points at segment(s) "
                         f"{bad[:10].tolist()}")
    return prob


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def block_diag_2(blocks: np.ndarray) -> np.ndarray:
    """(M, 2, 2) blocks -> (2M, 2M) block-diagonal matrix."""
    m = len(blocks)
    out = np.zeros((2 * m, 2 * m))
    for s_ in range(2):
        for t_ in range(2):
            out[2 * np.arange(m) + s_, 2 * np.arange(m) + t_] = blocks[:, s_, t_]
    return out
