"""Reproduce the paper's release-0.5 scenario and print its stick/slip summary."""

from lumped.solvers.closed_form import BinghamOscillator, integrate
from lumped.trajectory import summarize

osc = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)
for method in ("bdf1", "bdf2"):
    traj = integrate(osc, x0=0.5, dt=1e-4, t_end=5.0, method=method)
    s = summarize(traj)
    print(f"{method}: rests at x = {s.rest_position:.6g} (|x| <= tau/k = {osc.tau / osc.k})"
          f" from t = {s.last_stick_time:.4f} s; stuck for {s.stick_time:.4f} s in all")
