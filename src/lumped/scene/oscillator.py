r"""The paper's oscillator as a scene, in one line: :func:`bingham_oscillator`."""

from __future__ import annotations

from lumped.laws import get_law

from .network import GROUND, Element, Mass, Scene

__all__ = ["bingham_oscillator"]


def bingham_oscillator(m: float = 1.0, k: float = 100.0, gamma: float = 1.0,
                       tau: float = 1.0, x0: float = 0.0, v0: float = 0.0,
                       forcing: object = None) -> Scene:
    r"""One mass, a linear spring and a Bingham dashpot, both to ground (paper Fig. 1).

    .. math::

        m v' = F(t) - F_s - F_d, \quad x' = v, \quad F_s = k x, \quad
        v = \gamma\,(F_d - \operatorname{clip}(F_d, -\tau, \tau)),

    with ``tau = mu_s N_f`` the yield force. The mass is named ``"mass"``, the elements
    ``"spring"`` and ``"dashpot"``; both run from ground to the mass, so their forces are
    the paper's ``F_s`` and ``F_d`` (positive in tension, acting on the mass as ``-F``).
    ``method="auto"`` runs this scene with the closed form (``closed-bdf2``), and
    ``closed-bdf1`` is the paper's Algorithm 1.

    Parameters
    ----------
    m, k, gamma, tau : float
        Mass (kg, ``> 0``), stiffness (N/m, ``> 0``), Bingham fluidity (m/(N s), ``> 0``)
        and yield force (N, ``>= 0``).
    x0, v0 : float
        Initial displacement (m) and velocity (m/s).
    forcing : optional
        External force on the mass (N, positive towards ``+x``): anything
        :func:`lumped.scene.as_forcing` accepts (a callable such as
        :class:`lumped.scene.SineBurst`, a number, an expression in ``t``); ``None`` for
        a free oscillator.

    Returns
    -------
    Scene

    Raises
    ------
    ValueError, TypeError
        For a bad parameter (the message names it).

    Examples
    --------
    >>> from lumped import simulate
    >>> from lumped.scene import bingham_oscillator, paper_F2
    >>> scene = bingham_oscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0, forcing=paper_F2)
    >>> simulate(scene, dt=1e-3, t_end=5.0).method
    'closed-bdf2'
    """
    spring = get_law("linear_spring").bind(k=k)
    dashpot = get_law("bingham").bind(gamma=gamma, tau=tau)
    return Scene(
        [Mass("mass", m=m, x0=x0, v0=v0)],
        [Element("spring", spring, GROUND, "mass"), Element("dashpot", dashpot, GROUND, "mass")],
        forces=None if forcing is None else {"mass": forcing},
    )
