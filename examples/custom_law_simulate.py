"""A new law in one line, simulated: a mass on a spring with a quadratic-drag dashpot."""

from lumped import simulate
from lumped.laws import ElementLaw, get_law
from lumped.scene import Element, Mass, Scene

drag = ElementLaw("quadratic_drag", "dashpot", "F = c*q*Abs(q)", ["c"])  # F = c v |v|
scene = Scene(
    [Mass("mass", m=1.0, x0=0.5)],
    [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
     Element("drag", drag.bind(c=2.0), "ground", "mass")],
)
sol = simulate(scene, method="bdf2", dt=1e-3, t_end=5.0)
print(sol.status.value, sol.stats["newton_iterations"], "Newton iterations")
print("x(5) =", sol.x["mass"][-1], " F_drag(5) =", sol.F["drag"][-1])
sol.to_csv("custom_law.csv")
