"""Hand-written kernels following the `lumped.laws` contract (R, dR/dq, dR/dF).

`law(name, **p)` returns the real built-in law (the tests run against it); `bound(...)`
gives an independent hand-written kernel, used where a test needs a specific curve (the
cubic S law ``q = F^3 - F``) or a deliberately broken law."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class FakeLaw:
    name: str
    kind: str


@dataclass(frozen=True)
class FakeBound:
    law: FakeLaw
    params: dict = field(default_factory=dict)
    fn: object = None

    def kernel(self, q, F):
        return self.fn(q, F)


def _clip(F, lo, hi):
    return min(max(F, lo), hi)


def bound(name, **p):
    if name == "linear_spring":
        k = p["k"]
        return FakeBound(FakeLaw(name, "spring"), p, lambda q, F: (F - k * q, -k, 1.0))
    if name == "newtonian":
        c = p["c"]
        return FakeBound(FakeLaw(name, "dashpot"), p, lambda q, F: (F - c * q, -c, 1.0))
    if name == "bingham":
        g, tau = p["gamma"], p["tau"]

        def bingham(q, F):
            if F > tau:
                return q - g * (F - tau), 1.0, -g
            if F < -tau:
                return q - g * (F + tau), 1.0, -g
            return q, 1.0, 0.0

        return FakeBound(FakeLaw(name, "dashpot"), p, bingham)
    if name == "coulomb":
        tau, r = p["tau"], p["r"]

        def coulomb(q, F):
            y = F + r * q
            if y > tau:
                return F - tau, 0.0, 1.0
            if y < -tau:
                return F + tau, 0.0, 1.0
            return -r * q, -r, 0.0

        return FakeBound(FakeLaw(name, "dashpot"), p, coulomb)
    if name == "herschel_bulkley":
        g, tau, n = p["gamma"], p["tau"], p["n"]

        def hb(q, F):
            e = abs(F) - tau
            if e <= 0.0:
                return q, 1.0, 0.0
            s = 1.0 if F > 0 else -1.0
            return q - g * s * e**n, 1.0, -g * n * e ** (n - 1.0)

        return FakeBound(FakeLaw(name, "dashpot"), p, hb)
    if name == "string_spring":
        k, L = p["k"], p["L"]

        def string(q, F):
            if F / k < L:
                return q - F / k, 1.0, -1.0 / k
            return q - L, 1.0, 0.0

        return FakeBound(FakeLaw(name, "spring"), p, string)
    if name == "s_shaped":
        # q = F^3 - F: F is not a function of q (folds at F = +-1/sqrt(3))
        return FakeBound(FakeLaw(name, "spring"), p,
                         lambda q, F: (q - F**3 + F, 1.0, 1.0 - 3.0 * F * F))
    raise KeyError(name)


def law(name, **p):
    """The real built-in law if the law library exists, else the hand-written kernel."""
    try:
        from lumped.laws import get_law
    except ImportError:
        return bound(name, **p)
    return get_law(name).bind(**p)
