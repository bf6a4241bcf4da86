r"""Benchmark scenes beyond one mass: Bingham chains of two and three masses, and the
Maxwell example (issue 8, "beyond one mass").

A chain of ``n`` masses in series; mass ``i`` hangs on mass ``i - 1`` (mass 1 on ground)
by a linear spring and a Bingham dashpot in parallel, and the last mass is shaken by a
sine burst switched off at ``t_off``::

    ground --[k1 | bingham g1, tau1]-- m1 --[k2 | bingham g2, tau2]-- m2 ... mn <- A sin(w t)

Every element is drawn from the node nearer ground to the next one, so ``q = x_b - x_a``
(springs) or ``v_b - v_a`` (dashpots) is the stretch of that link and ``F > 0`` is
tension (:mod:`lumped.scene.network`). The parameters are chosen so that every dashpot
both sticks and slips while the burst is on, and every one sticks for good after it.

The Maxwell scene is ``examples/maxwell.toml`` (a mass on a spring and a Newtonian
dashpot in series through a massless junction), built here without reading the file so
that the benchmark does not depend on the working directory; a test checks that both
agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..laws import get_law
from ..scene import Element, Junction, Mass, Scene
from ..scene.forcing import SineBurst

__all__ = [
    "NetworkScene",
    "NETWORK_SCENES",
    "bingham_chain",
    "maxwell_example",
    "maxwell_exact",
    "network_scene",
]

#: (m, k, gamma, tau) of each link of the chains, from ground outwards.
CHAIN_LINKS: tuple[tuple[float, float, float, float], ...] = (
    (1.0, 40.0, 0.5, 1.5),
    (0.5, 20.0, 1.0, 0.6),
    (0.8, 30.0, 2.0, 0.4),
)
#: The burst on the last mass: amplitude, angular frequency, switch-off time.
CHAIN_FORCING = SineBurst(4.0, 2.0 * math.pi, 3.0)


def bingham_chain(n: int, *, forcing: SineBurst = CHAIN_FORCING) -> Scene:
    r"""A chain of ``n`` (1 to 3) masses joined by springs and Bingham dashpots.

    Link ``i`` (``i = 1..n``) joins node ``m{i-1}`` (``ground`` for ``i = 1``) to
    ``m{i}`` with ``linear_spring(k_i)`` (element ``s{i}``) and ``bingham(gamma_i,
    tau_i)`` (element ``d{i}``) from :data:`CHAIN_LINKS`; the last mass carries
    ``forcing``. The masses start at rest at ``x = 0``. Equations of mass ``i``:

    .. math:: m_i v_i' = F_{s,i+1} + F_{d,i+1} - F_{s,i} - F_{d,i} + f_i(t),

    with ``F_{s,i} = k_i (x_i - x_{i-1})`` and ``v_i - v_{i-1} = \gamma_i (F_{d,i} -
    \operatorname{clip}(F_{d,i}, -\tau_i, \tau_i))`` (the link ``n + 1`` absent).
    """
    if not (isinstance(n, int) and 1 <= n <= len(CHAIN_LINKS)):
        raise ValueError(f"`n` must be an int from 1 to {len(CHAIN_LINKS)}, got {n!r}")
    lin, bing = get_law("linear_spring"), get_law("bingham")
    nodes, elements = [], []
    for i, (m, k, gamma, tau) in enumerate(CHAIN_LINKS[:n], start=1):
        a, b = ("ground" if i == 1 else f"m{i - 1}"), f"m{i}"
        nodes.append(Mass(b, m=m))
        elements += [Element(f"s{i}", lin.bind(k=k), a, b),
                     Element(f"d{i}", bing.bind(gamma=gamma, tau=tau), a, b)]
    return Scene(nodes, elements, {f"m{n}": forcing})


def maxwell_example(m: float = 1.0, k: float = 50.0, c: float = 2.0,
                    x0: float = 0.3) -> Scene:
    r"""``examples/maxwell.toml``: ``ground --[newtonian c]-- j --[spring k]-- mass``.

    The mass starts at ``x0`` at rest, the junction at 0. State ``(x, v, x_j)``:
    ``x' = v``, ``m v' = -k (x - x_j)``, ``c x_j' = k (x - x_j)``, a linear system whose
    exact solution is a matrix exponential.
    """
    return Scene(
        [Mass("mass", m=m, x0=x0), Junction("j", x0=0.0)],
        [Element("dashpot", get_law("newtonian").bind(c=c), "ground", "j"),
         Element("spring", get_law("linear_spring").bind(k=k), "j", "mass")],
    )


def maxwell_exact(t: np.ndarray, m: float = 1.0, k: float = 50.0, c: float = 2.0,
                  x0: float = 0.3) -> np.ndarray:
    r"""Exact ``(x, x_j)`` of :func:`maxwell_example` at the times ``t``.

    .. math::  y(t) = e^{A t} y_0, \qquad y = (x, v, x_j), \qquad
               A = \begin{pmatrix} 0 & 1 & 0 \\ -k/m & 0 & k/m \\ k/c & 0 & -k/c
               \end{pmatrix},

    with ``y_0 = (x0, 0, 0)``; returns an array of shape ``(len(t), 2)``.
    """
    from scipy.linalg import expm

    A = np.array([[0.0, 1.0, 0.0], [-k / m, 0.0, k / m], [k / c, 0.0, -k / c]])
    y0 = np.array([x0, 0.0, 0.0])
    return np.array([expm(A * float(tt)) @ y0 for tt in np.asarray(t, dtype=float)])[:, [0, 2]]


@dataclass(frozen=True)
class NetworkScene:
    """A named scene of the multi-mass benchmark.

    ``t_end`` is the span scored; the fixed-step BDF2 ladder runs on ``[0, bdf_t_end]``
    with ``dt = 1e-3 / 2^j`` for ``j = 2 .. bdf_finest`` (BDF2 converges at order 1 across
    stick-slip events, so the chains need ``dt`` near 1e-6 for errors near 1e-7, and the
    compiled BDF2 keeps every step in memory: a shorter span keeps that affordable).
    """

    name: str
    n_masses: int
    t_end: float
    bdf_t_end: float
    bdf_finest: int
    note: str

    def build(self) -> Scene:
        """A fresh :class:`~lumped.scene.Scene`."""
        return maxwell_example() if self.name == "maxwell" else bingham_chain(self.n_masses)


NETWORK_SCENES: tuple[NetworkScene, ...] = (
    NetworkScene("chain-2", 2, 5.0, 1.0, 11,
                 "two masses, Bingham links; burst on m2 until t = 3"),
    NetworkScene("chain-3", 3, 5.0, 1.0, 11,
                 "three masses, Bingham links; burst on m3 until t = 3"),
    NetworkScene("maxwell", 1, 5.0, 5.0, 8,
                 "examples/maxwell.toml: Maxwell element, junction"),
)


def network_scene(name: str) -> NetworkScene:
    """The entry of :data:`NETWORK_SCENES` called ``name``."""
    for sc in NETWORK_SCENES:
        if sc.name == name:
            return sc
    raise ValueError(f"`name` must be one of {[s.name for s in NETWORK_SCENES]}, got {name!r}")
