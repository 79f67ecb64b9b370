"""Gaussian smoothing of an angle sequence with mirror padding (the source's post-processing).

The source smooths the PSO result with a Gaussian kernel and pads both ends with mirrored
samples "to simulate the continuation of the data beyond its ends". That is scipy's
``mode="mirror"`` padding (d c b | a b c d | c b a), so the library call does it.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

__all__ = ["gaussian_smooth_mirror"]


def gaussian_smooth_mirror(values: np.ndarray, sigma: float) -> np.ndarray:
    """Smooth each column of ``values`` along axis 0.

    Args:
        values: (M,) or (M, k) samples in path order (e.g. theta_A, theta_B [rad]).
        sigma: kernel standard deviation in samples (CL points); 0 returns a copy.

    Returns:
        Array like ``values``. The kernel weights are positive and sum to one, so a sequence
        inside a box stays inside it.
    """
    v = np.asarray(values, float)
    if sigma <= 0:
        return v.copy()
    return gaussian_filter1d(v, sigma=sigma, axis=0, mode="mirror")
