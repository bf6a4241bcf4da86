r"""One slip arc of the exact reference: the closed-form motion ``x(t), v(t)`` of the
mass while the dashpot slips in one direction (homogeneous part, particular solution
of the sine forcing, Duhamel form near resonance), and its sampling times.
"""

from __future__ import annotations

import math

import numpy as np

from .model import Params

__all__ = []


EPS = np.finfo(float).eps
#: Samples per half period of the homogeneous motion / per forcing period used to bracket roots.
_SAMPLES_PER_HALF_PERIOD = 16
_SAMPLES_PER_FORCING_PERIOD = 32
CHUNK = 512
#: Resonance magnification above which the forced response is written as a Duhamel integral.
_NEAR_RESONANCE = 8.0


class SlipArc:
    r"""Closed-form solution of ``m x'' + c x' + k x = F(t) - s tau`` from ``(t0, x0, v0)``."""

    def __init__(self, p: Params, s: int, forced: bool, t0: float, x0: float, v0: float):
        self.p, self.s, self.forced, self.t0, self.v0 = p, s, forced, t0, v0
        m, k, c = p.m, p.k, p.c
        self.x_eq = -s * p.tau / k
        a = c / (2.0 * m)
        w0 = math.sqrt(k / m)
        self.a, self.w0, self.w0sq = a, w0, k / m
        if a < w0:
            self.regime = "under"
            self.wd = math.sqrt((w0 - a) * (w0 + a))
        elif a == w0:
            self.regime = "critical"
        else:
            self.regime = "over"
            beta = math.sqrt((a - w0) * (a + w0))
            self.beta = beta
            self.r1 = -self.w0sq / (a + beta)  # slow root, without cancellation
            self.r2 = -(a + beta)
        # Forced response.  Away from resonance: the steady sinusoid
        # u_p = P sin(w t) + Q cos(w t).  Near resonance (magnification
        # (k + m w^2) / sqrt(D) > _NEAR_RESONANCE, only possible when under-damped) u_p is
        # huge and cancels against the free motion, so the response from rest at t0 is
        # written as a Duhamel integral instead (see _duhamel).
        self.P = self.Q = 0.0
        self.w = p.w if forced else 0.0
        self.duhamel = False
        amp_p = 0.0
        if forced:
            w = p.w
            det = k - m * w * w
            D = det * det + (c * w) ** 2
            if self.regime == "under" and (k + m * w * w) > _NEAR_RESONANCE * math.sqrt(D):
                self.duhamel = True
                self.lam = complex(-a, self.wd)
                amp_p = abs(p.A) / (k + m * w * w)
            else:
                self.P = p.A * det / D
                self.Q = -p.A * c * w / D
                amp_p = math.hypot(self.P, self.Q)
        up0, dup0 = self._particular(t0, math)
        self.u0 = x0 - self.x_eq - up0
        self.du0 = v0 - dup0
        self.v_scale = max(abs(v0), abs(self.du0), w0 * abs(self.u0),
                           amp_p * max(abs(self.w), w0), 1e-300)

    # -- formulas, generic over ``xp`` in {math, numpy} -------------------------------------
    def _particular(self, t, xp):
        """Steady response ``(u_p, u_p')`` (zero on unforced or Duhamel arcs)."""
        w = self.w
        if w == 0.0 or self.duhamel:
            return 0.0 * t, 0.0 * t
        sn, cs = xp.sin(w * t), xp.cos(w * t)
        return self.P * sn + self.Q * cs, w * (self.P * cs - self.Q * sn)

    def _duhamel(self, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r"""Response ``(u_f, u_f')`` at ``t0 + h`` to ``A sin(w t) / m`` from rest at ``t0``.

        With ``lambda = -a + i w_d`` and ``g(s) = Im(e^{lambda s}) / w_d`` the impulse
        response, ``u_f = (A/m) Im(e^{i w t0} J)``, ``J = (K(lambda) - K(conj lambda)) /
        (2 i w_d)`` and ``K(mu) = int_0^h e^{mu (h - s)} e^{i w s} ds
        = h e^{mu h} phi1((i w - mu) h)``, ``phi1(z) = expm1(z) / z``: no cancellation
        however close ``i w`` is to ``lambda`` (exact undamped resonance included, where
        ``phi1(0) = 1`` gives the secular term).  ``u_f' = (A/m) Im(e^{i w t0} J')`` with
        ``J' = (lambda K(lambda) - conj(lambda) K(conj lambda)) / (2 i w_d)``.
        """
        h = np.asarray(h, dtype=float)
        lam, lamc, w = self.lam, self.lam.conjugate(), self.w

        def K(mu):
            z = (1j * w - mu) * h
            safe = np.where(z == 0, 1.0, z)
            phi1 = np.where(z == 0, 1.0, np.expm1(safe) / safe)
            return h * np.exp(mu * h) * phi1

        k1, k2 = K(lam), K(lamc)
        scale = self.p.A / self.p.m * np.exp(1j * w * self.t0) / (2j * self.wd)
        return (scale * (k1 - k2)).imag, (scale * (lam * k1 - lamc * k2)).imag

    def _propagator(self, h, xp):
        """Entries of ``Phi(h)`` for ``u'' + 2a u' + w0^2 u = 0``."""
        a, w0sq = self.a, self.w0sq
        if self.regime == "under":
            wd = self.wd
            e = xp.exp(-a * h)
            cs = e * xp.cos(wd * h)
            sw = e * xp.sin(wd * h) / wd
            return cs + a * sw, sw, -w0sq * sw, cs - a * sw
        if self.regime == "critical":
            e = xp.exp(-a * h)
            return e * (1.0 + a * h), e * h, -w0sq * e * h, e * (1.0 - a * h)
        beta, r1 = self.beta, self.r1
        e1 = xp.exp(r1 * h)
        e2 = xp.exp(self.r2 * h)
        phi12 = -e1 * xp.expm1(-2.0 * beta * h) / (2.0 * beta)  # (e1 - e2) / (2 beta)
        return e2 + (a + beta) * phi12, phi12, -w0sq * phi12, e2 + r1 * phi12

    def state(self, t, xp=np):
        """``(x, v)`` at ``t`` (array with ``xp=numpy`` or float with ``xp=math``)."""
        h = t - self.t0
        p11, p12, p21, p22 = self._propagator(h, xp)
        if self.duhamel:
            up, dup = self._duhamel(h)
            if xp is math:
                up, dup = float(up), float(dup)
        else:
            up, dup = self._particular(t, xp)
        u = p11 * self.u0 + p12 * self.du0 + up
        du = p21 * self.u0 + p22 * self.du0 + dup
        return u + self.x_eq, du

    def v_scalar(self, t: float) -> float:
        return self.state(t, math)[1]

    def accel(self, t: np.ndarray, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``v'`` from the balance of momentum at the samples ``(t, x, v)`` of this arc."""
        p = self.p
        F = p.A * np.sin(p.w * t) if self.forced else 0.0
        return (F - p.k * x - self.s * p.tau - p.c * v) / p.m

    def accel_scalar(self, t: float) -> float:
        x, v = self.state(t, math)
        p = self.p
        return (p.force(t, self.forced) - p.k * x - self.s * p.tau - p.c * v) / p.m

    # -- sampling for root brackets -------------------------------------------------------------
    def sample_times(self, t_stop: float):
        """Yield chunks of increasing sample times in ``(t0, t_stop]``, ending at ``t_stop``.

        Spacing: 1/16 of the homogeneous half period ``pi / w_d`` and 1/32 of the forcing
        period, preceded by a geometric ramp from 1/16 of the fastest time scale (a fast
        over-damped transient).  Unforced and not oscillating, ``v`` is a sum of two
        exponentials (at most one sign change) and the geometric ramp alone suffices.
        """
        span = t_stop - self.t0
        if span <= 0.0:
            yield np.array([t_stop])
            return
        fast_rate = {"under": self.w0, "critical": self.a}.get(self.regime)
        if fast_rate is None:
            fast_rate = -self.r2
        h_fast = 1.0 / (_SAMPLES_PER_HALF_PERIOD * fast_rate)
        a0 = self.accel_scalar(self.t0)
        if self.v0 * a0 < 0.0:  # decelerating: v may reach 0 after about |v0 / a0|
            h_fast = min(h_fast, 0.25 * abs(self.v0 / a0))
        steps = []
        if self.regime == "under":
            steps.append(math.pi / self.wd / _SAMPLES_PER_HALF_PERIOD)
        if self.w != 0.0:
            steps.append(2.0 * math.pi / abs(self.w) / _SAMPLES_PER_FORCING_PERIOD)
        h = min(steps) if steps else span
        h_fast = max(h_fast, h * 2.0**-64)
        if h_fast < h:
            ramp = np.geomspace(h_fast, h, int(math.ceil(math.log2(h / h_fast))) + 1)[:-1]
            ramp = ramp[ramp < span]
            if ramp.size:
                yield self.t0 + ramp
        n_uniform = int(math.ceil(span / h))
        for start in range(0, n_uniform, CHUNK):
            stop = min(start + CHUNK, n_uniform)
            rel = np.arange(start + 1, stop + 1) * h
            ts = self.t0 + rel[rel < span]
            if stop == n_uniform:
                ts = np.append(ts, t_stop)
            yield ts
