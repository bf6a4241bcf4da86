"""Declare a new element law in a few lines: a quadratic-drag dashpot F = c q |q|."""

from lumped.laws import ElementLaw

drag = ElementLaw(
    "quadratic_drag", "dashpot", "F = c*q*Abs(q)", ["c"],
    description="quadratic drag F = c v |v|", domains={"c": "positive"},
)
print(drag)                          # quadratic_drag (dashpot): F - c*q*Abs(q) = 0
print(drag.latex())                  # F - c q \left|{q}\right| = 0

bound = drag.bind(c=0.5)
R, dR_dq, dR_dF = bound.kernel(2.0, 2.0)   # (R, dR/dq, dR/dF) at q = 2, F = 2
print(R, dR_dq, dR_dF)               # 0.0 -2.0 1.0
print(bound.kernel.__source__)       # the generated plain-Python kernel
