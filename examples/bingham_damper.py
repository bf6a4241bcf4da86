r"""A Bingham damper under stepped-sine displacement at three amplitudes.

**The rig.** The damper (``bingham``, ``gamma``, ``tau``) joins the shaken ground to a
reaction mass ``M`` and nothing else. The ground moves as ``x_g = U sin(omega t)``
(a displacement sine, differentiated exactly), and the mass starts at absolute rest
(relative velocity ``v0 = -U omega``). The mass is so heavy that it stays put: its
absolute displacement is bounded by ``F_max / (M omega^2)``, printed from the run
(``sol.absolute.x``), so the damper's elongation, the mass's relative displacement
``q = x - x_g ~ -U sin(omega t)``, is the prescribed one to that relative error. Each
amplitude is one run of ``N`` cycles (a stepped sine: the velocity would jump if the
amplitude changed inside a run).

**Closed forms.** Under ``qdot = -U omega cos(omega t)`` the Bingham force is
``F = sgn(qdot) (tau + |qdot| / gamma)``, so per cycle

.. math::  E_d = 4 \tau U + \pi U^2 \omega / \gamma, \qquad
           F_0 = \tau + U \omega / \gamma, \qquad
           \zeta_{eq} = \frac{E_d}{2 \pi F_0 U},

with the secant stiffness ``k_eff = F_0 / U`` (:mod:`lumped.post.loops`). Writes
``docs/bingham_damper.png`` (or ``--out``): force-displacement and force-velocity
loops, and energy per cycle and ``zeta_eq`` against amplitude, with the closed forms.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.post import cycles, hysteresis
from lumped.scene import GroundMotion, SineBurst

HERE = Path(__file__).resolve().parent
GAMMA, TAU = 0.01, 50.0            # m/(N s), N: c = 1/gamma = 100 N s/m above yield
OMEGA = 2.0 * math.pi              # 1 Hz
M_REACTION = 1e7                   # kg
AMPLITUDES = (0.01, 0.03, 0.1)     # m
N_CYCLES = 3


def rig(U: float) -> Scene:
    return Scene([Mass("reaction", m=M_REACTION, v0=-U * OMEGA)],
                 [Element("damper", get_law("bingham").bind(gamma=GAMMA, tau=TAU),
                          "ground", "reaction")],
                 ground_motion=GroundMotion(displacement=SineBurst(U, OMEGA)))


def exact(U: float) -> tuple[float, float]:
    E = 4 * TAU * U + math.pi * U * U * OMEGA / GAMMA
    return E, E / (2 * math.pi * (TAU + U * OMEGA / GAMMA) * U)


def main(out: Path) -> list[dict[str, float]]:
    T = 2 * math.pi / OMEGA
    rows, sols = [], []
    for U in AMPLITUDES:
        sol = simulate(rig(U), method="radau5", t_end=N_CYCLES * T, dt=T / 400, rtol=1e-8)
        rep = cycles(sol, "damper", omega=OMEGA)
        E, zeta = exact(U)
        drift = float(np.abs(sol.absolute.x["reaction"]).max())
        rows.append({"U": U, "E_d": rep.cycles[-1].energy, "E_exact": E,
                     "zeta_eq": rep.cycles[-1].zeta_eq, "zeta_exact": zeta,
                     "rig_error": drift / U})
        sols.append(sol)
        print(f"U = {U:g} m: E_d = {rows[-1]['E_d']:.6g} J (exact {E:.6g}), zeta_eq = "
              f"{rows[-1]['zeta_eq']:.5f} (exact {zeta:.5f}); reaction mass moved "
              f"{drift:.2e} m = {drift / U:.1e} U")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(12.0, 3.8), layout="constrained")
    for U, sol in zip(AMPLITUDES, sols, strict=True):
        loop = hysteresis(sol, "damper", t0=(N_CYCLES - 1) * T, t1=N_CYCLES * T)
        ax[0].plot(loop.elongation * 1e3, loop.force, label=f"U = {U * 1e3:g} mm")
        ax[1].plot(loop.rate, loop.force, label=f"U = {U * 1e3:g} mm")
    ax[0].set(xlabel="elongation q (mm)", ylabel="damper force F (N)",
              title="force-displacement")
    ax[1].set(xlabel="elongation rate (m/s)", ylabel="damper force F (N)",
              title="force-velocity")
    ax[0].legend(fontsize=8)
    Us = np.linspace(AMPLITUDES[0], AMPLITUDES[-1], 100)
    ex = np.array([exact(float(u)) for u in Us])
    ax[2].plot(Us * 1e3, ex[:, 0], "C0-", lw=0.8, label="E_d exact")
    ax[2].plot([r["U"] * 1e3 for r in rows], [r["E_d"] for r in rows], "C0o", label="E_d")
    ax[2].set(xlabel="amplitude U (mm)", ylabel="energy per cycle (J)")
    twin = ax[2].twinx()
    twin.plot(Us * 1e3, ex[:, 1], "C3-", lw=0.8, label="zeta_eq exact")
    twin.plot([r["U"] * 1e3 for r in rows], [r["zeta_eq"] for r in rows], "C3s",
              label="zeta_eq")
    twin.set_ylabel("equivalent damping ratio")
    ax[2].legend(loc="upper left", fontsize=8)
    twin.legend(loc="center right", fontsize=8)
    ax[2].set_title("per cycle, against amplitude")
    fig.suptitle(f"Bingham damper (gamma = {GAMMA:g} m/(N s), tau = {TAU:g} N) at 1 Hz")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE.parent / "docs" / "bingham_damper.png")
    main(parser.parse_args().out)
