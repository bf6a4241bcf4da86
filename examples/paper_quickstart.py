"""Reproduce the paper's release-0.5 scenario and print where and when the mass comes to rest."""

from lumped import simulate
from lumped.scene import bingham_oscillator

scene = bingham_oscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0, x0=0.5)
for method in ("closed-bdf1", "closed-bdf2"):
    sol = simulate(scene, method=method, dt=1e-4, t_end=5.0)
    sticks = sol.stick_intervals("dashpot")
    start, end = sticks[-1]
    stuck = sum(b - a for a, b in sticks)
    ledger = sol.energy()
    print(f"{method}: rests at x = {sol.x['mass'][-1]:.6g} (|x| <= tau/k = {1.0 / 100.0})"
          f" from t = {start:.4f} s to {end:g} s; stuck for {stuck:.4f} s in all;"
          f" dissipated {ledger.dissipated['dashpot'][-1]:.4f} J of"
          f" {0.5 * 100.0 * 0.5**2:.4f} J")
