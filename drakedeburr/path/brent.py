"""Brent's bounded scalar minimisation run in lockstep over many independent problems (the
true chord heights of :mod:`drakedeburr.path.edge_curve`)."""

from __future__ import annotations

import numpy as np

__all__ = ["minimize_bounded_batch"]


def minimize_bounded_batch(func, lo: np.ndarray, hi: np.ndarray, xatol: np.ndarray,
                           maxfun: int = 500) -> np.ndarray:
    """Minimum values of M independent bounded scalar problems, (M,).

    ``func`` maps (M,) points to (M,) values (problem m sees only entry m). This is scipy's
    ``minimize_scalar(method="bounded")`` (Brent's method, scipy 1.17 ``_minimize_scalar_bounded``)
    step for step, run in lockstep over the problems: every problem gets the very same iterates
    and result as its own scipy call. Written by hand because scipy solves one problem per
    call (~0.4 ms of Python each; the true chord heights of a plan are hundreds of them).
    """
    sqrt_eps, golden_mean = np.sqrt(2.2e-16), 0.5 * (3.0 - np.sqrt(5.0))
    a, b = np.array(lo, float), np.array(hi, float)
    xf = nfc = fulc = a + golden_mean * (b - a)
    rat = e = np.zeros_like(a)
    fx = ffulc = fnfc = func(xf)
    num = 1
    xm = 0.5 * (a + b)
    tol1 = sqrt_eps * np.abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    act = np.abs(xf - xm) > (tol2 - 0.5 * (b - a))
    with np.errstate(divide="ignore", invalid="ignore"):
        while act.any():
            # parabolic fit (used where |e| > tol1 and the parabola is acceptable)
            r = (xf - nfc) * (fx - ffulc)
            q = (xf - fulc) * (fx - fnfc)
            p = (xf - fulc) * q - (xf - nfc) * r
            q = 2.0 * (q - r)
            p = np.where(q > 0.0, -p, p)
            q = np.abs(q)
            para = (np.abs(e) > tol1) & (np.abs(p) < np.abs(0.5 * q * e)) & (p > q * (a - xf)) \
                & (p < q * (b - xf))
            rat_p = (p + 0.0) / q
            x_p = xf + rat_p
            near = ((x_p - a) < tol2) | ((b - x_p) < tol2)
            rat_p = np.where(near, tol1 * (np.sign(xm - xf) + ((xm - xf) == 0)), rat_p)
            e_g = np.where(xf >= xm, a - xf, b - xf)  # golden-section step
            e_new = np.where(para, rat, e_g)
            rat = np.where(act, np.where(para, rat_p, golden_mean * e_g), rat)
            e = np.where(act, e_new, e)
            x = xf + (np.sign(rat) + (rat == 0)) * np.maximum(np.abs(rat), tol1)
            fu = func(x)
            num += 1
            better = act & (fu <= fx)
            worse = act & ~(fu <= fx)
            right = x >= xf
            a = np.where(better & right, xf, np.where(worse & ~right, x, a))
            b = np.where(better & ~right, xf, np.where(worse & right, x, b))
            c1 = worse & ((fu <= fnfc) | (nfc == xf))
            c2 = worse & ~c1 & ((fu <= ffulc) | (fulc == xf) | (fulc == nfc))
            fulc, ffulc = (np.where(better | c1, nfc, np.where(c2, x, fulc)),
                           np.where(better | c1, fnfc, np.where(c2, fu, ffulc)))
            nfc, fnfc = (np.where(better, xf, np.where(c1, x, nfc)),
                         np.where(better, fx, np.where(c1, fu, fnfc)))
            xf, fx = np.where(better, x, xf), np.where(better, fu, fx)
            xm = 0.5 * (a + b)
            tol1 = sqrt_eps * np.abs(xf) + xatol / 3.0
            tol2 = 2.0 * tol1
            act = act & (np.abs(xf - xm) > (tol2 - 0.5 * (b - a)))
            if num >= maxfun:
                break
    return fx
