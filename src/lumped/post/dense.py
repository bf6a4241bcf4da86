r"""Dense output of a fixed-step run: piecewise cubic Hermite between the samples.

On ``[t_k, t_{k+1}]`` with ``h = t_{k+1} - t_k`` and ``s = (t - t_k) / h``,

.. math::

    y(t) = h_{00}(s)\, y_k + h_{10}(s)\, h\, y'_k + h_{01}(s)\, y_{k+1}
           + h_{11}(s)\, h\, y'_{k+1},

    h_{00} = 2s^3 - 3s^2 + 1,\quad h_{10} = s^3 - 2s^2 + s,\quad
    h_{01} = -2s^3 + 3s^2,\quad h_{11} = s^3 - s^2 .

What each column uses as its derivative ``y'``:

* ``x_i`` of every node: the sampled velocity ``v_i`` (kinematics ``x' = v``);
* ``v_i`` of a mass: the acceleration from the momentum balance at the sample,
  ``a_i = (f_i(t) + sum_{a_e = i} F_e - sum_{b_e = i} F_e) / m_i``;
* ``v_i`` of a junction and every force ``F_e``: no derivative is known (a junction's
  velocity and a force may jump where a law switches branch), so they are interpolated
  linearly between samples;
* ``t``: ``t`` itself.

The interpolant passes through every sample exactly and is continuous; with ``x`` and
``v`` it is of order 3 between samples for a smooth motion, so the method's own error
(order 1 or 2 for the BDF methods) dominates.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from lumped.scene import Mass, Scene

from .columns import net_forces, v_col, x_col

__all__ = ["HermiteDense", "hermite_dense", "check_times"]


def check_times(t: object, t_first: float, t_last: float) -> tuple[np.ndarray, bool]:
    """``t`` as a 1-D float array (and whether it was a scalar); ValueError naming ``t``
    for a non-finite time or one outside ``[t_first, t_last]``."""
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"`t` must be a real number or an array of them, got {t!r}") from None
    scalar = arr.ndim == 0
    arr = np.atleast_1d(arr)
    if arr.ndim != 1:
        raise ValueError(f"`t` must be a scalar or a 1-D array, got shape {arr.shape}")
    # (the common case in two reductions: a NaN makes both comparisons false)
    if arr.size and arr.min() >= t_first and arr.max() <= t_last:
        return arr, scalar
    bad = ~np.isfinite(arr) | (arr < t_first) | (arr > t_last)
    if bad.any():
        raise ValueError(
            f"`t` must lie in [{t_first!r}, {t_last!r}] (the solved interval), "
            f"got {arr[bad][0]!r}"
        )
    return arr, scalar


def hermite_dense(scene: Scene, data: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Return ``dense(t) -> (len(t), n_cols)``, the cubic Hermite interpolant of ``data``.

    Parameters
    ----------
    scene : Scene
        The scene that produced ``data`` (masses, elements and forcing give the
        accelerations).
    data : numpy.ndarray
        ``(n_samples, n_cols)`` samples with increasing times in column 0.

    Returns
    -------
    callable
        ``dense(t)`` for a 1-D array ``t`` inside ``[data[0, 0], data[-1, 0]]`` (checked
        by the caller, see :func:`check_times`); rows laid out like ``data``.
    """
    data = np.asarray(data, dtype=float)
    n_nodes = len(scene.nodes)
    deriv = np.full(data.shape, np.nan)  # NaN: interpolate that column linearly
    deriv[:, 0] = 1.0
    net = net_forces(scene, data) if len(data) > 1 else None
    for i, node in enumerate(scene.nodes):
        deriv[:, x_col(i)] = data[:, v_col(i)]
        if isinstance(node, Mass) and net is not None:
            deriv[:, v_col(i)] = net[:, i] / node.m
    hermite = ~np.isnan(deriv[0]) if len(data) else np.zeros(data.shape[1], bool)
    hermite[1 + 2 * n_nodes:] = False
    times = data[:, 0]

    def dense(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        if len(times) == 1:
            return np.repeat(data[:1], len(t), axis=0)
        k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
        h = times[k + 1] - times[k]  # zero only for a repeated time (a jump): take the later row
        s = np.where(h > 0, (t - times[k]) / np.where(h > 0, h, 1.0), 1.0)[:, None]
        y0, y1 = data[k], data[k + 1]
        out = y0 + s * (y1 - y0)  # linear for every column, then Hermite where known
        d0, d1 = deriv[k][:, hermite], deriv[k + 1][:, hermite]
        s2, s3 = s * s, s * s * s
        hh = h[:, None]
        out[:, hermite] = ((2 * s3 - 3 * s2 + 1) * y0[:, hermite]
                           + (s3 - 2 * s2 + s) * hh * d0
                           + (-2 * s3 + 3 * s2) * y1[:, hermite]
                           + (s3 - s2) * hh * d1)
        out[:, 0] = t
        return out

    return dense


class HermiteDense:
    """:func:`hermite_dense` as a picklable object (a :class:`~lumped.result.Solution`
    that carries it travels between processes): keeps ``scene`` and ``data``, builds the
    interpolant on the first call.

    Used for samples with extra rows, e.g. the states just before and after each impact
    of a fixed-step run (repeated times: the later row holds from that time on)."""

    def __init__(self, scene: Scene, data: np.ndarray) -> None:
        self.scene = scene
        self.data = np.asarray(data, dtype=float)
        self._dense: Callable[[np.ndarray], np.ndarray] | None = None

    def __call__(self, t: np.ndarray) -> np.ndarray:
        if self._dense is None:
            self._dense = hermite_dense(self.scene, self.data)
        return self._dense(t)

    def __getstate__(self) -> dict:
        return {"scene": self.scene, "data": self.data, "_dense": None}
