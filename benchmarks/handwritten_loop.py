"""The limit for the compiled closed form: Algorithm 1 written by hand as one numba loop.

Everything that does not change from step to step is hoisted out of the loop (``m/dt``,
``1/(a + c/gamma)``, ``k dt``), the forcing is the sine burst written inline, and nothing
is stored: the loop returns the final state. No library code is called, so it is the
fastest plain Algorithm 1 on this machine; ``benchmarks/sweep_speed.py`` times the
library's compiled step against it.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, nogil=True)
def algorithm1_loop(m, k, gamma, tau, dt, n, x, v, amplitude, omega, t_off):
    """``n`` backward-Euler steps of the forced Bingham oscillator; returns ``(x, v)``."""
    m_dt = m / dt
    c = dt / m
    slip = c / (1.0 + dt * dt * k / m + c / gamma)
    for i in range(1, n + 1):
        t = i * dt
        F = amplitude * math.sin(omega * t) if t <= t_off else 0.0
        F_tilde = m_dt * v + F - k * x
        if F_tilde > tau:
            v = slip * (F_tilde - tau)
        elif F_tilde < -tau:
            v = slip * (F_tilde + tau)
        else:
            v = 0.0
        x += dt * v
    return x, v
