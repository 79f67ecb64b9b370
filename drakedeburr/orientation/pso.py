"""Particle swarm optimisation, the source's baseline solver (50 particles, 200 iterations,
inertia 0.8, c1 = c2 = 2).

Written here because the paper's exact PSO variant (global-best, positions clipped to the box)
is a dozen lines and no well-kept library exposes it with a vectorised objective over the
swarm; the objective of every model takes a (P, n) batch.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["PsoOptions", "PsoResult", "pso_minimize"]


@dataclass(frozen=True)
class PsoOptions:
    """Swarm settings (source defaults). ``v_max_fraction`` caps |velocity| per coordinate at
    that fraction of the box width (common practice; the source gives no cap)."""

    particles: int = 50
    iterations: int = 200
    inertia: float = 0.8
    c1: float = 2.0
    c2: float = 2.0
    v_max_fraction: float = 0.2
    seed: int = 0


@dataclass(frozen=True)
class PsoResult:
    x: np.ndarray
    objective: float
    history: np.ndarray  # (iterations + 1,) best objective after each iteration
    evaluations: int


def pso_minimize(
    f: Callable[[np.ndarray], np.ndarray],
    lower: np.ndarray,
    upper: np.ndarray,
    options: PsoOptions = PsoOptions(),
    x0: np.ndarray | None = None,
) -> PsoResult:
    """Minimise ``f`` over the box [lower, upper] with a global-best PSO.

    Args:
        f: batch objective, (P, n) -> (P,).
        lower, upper: (n,) box.
        options: swarm settings; the run is reproducible from ``options.seed``.
        x0: optional (n,) point placed as particle 0.

    Returns:
        The best position found and its objective.
    """
    rng = np.random.default_rng(options.seed)
    lo = np.asarray(lower, float)
    hi = np.asarray(upper, float)
    width = hi - lo
    P = options.particles
    x = lo + rng.random((P, lo.size)) * width
    if x0 is not None:
        x[0] = np.clip(x0, lo, hi)
    v_max = options.v_max_fraction * width
    v = (rng.random((P, lo.size)) * 2 - 1) * v_max
    fx = f(x)
    pbest, pbest_f = x.copy(), fx.copy()
    g = int(np.argmin(fx))
    gbest, gbest_f = x[g].copy(), float(fx[g])
    history = [gbest_f]
    for _ in range(options.iterations):
        r1 = rng.random(x.shape)
        r2 = rng.random(x.shape)
        v = options.inertia * v + options.c1 * r1 * (pbest - x) + options.c2 * r2 * (gbest - x)
        np.clip(v, -v_max, v_max, out=v)
        x = np.clip(x + v, lo, hi)
        fx = f(x)
        better = fx < pbest_f
        pbest[better] = x[better]
        pbest_f[better] = fx[better]
        g = int(np.argmin(pbest_f))
        if pbest_f[g] < gbest_f:
            gbest, gbest_f = pbest[g].copy(), float(pbest_f[g])
        history.append(gbest_f)
    return PsoResult(gbest, gbest_f, np.asarray(history), P * (options.iterations + 1))
