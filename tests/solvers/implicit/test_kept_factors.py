"""The consistent initial state's Jacobians factorised once (issue 27): a scene with a new
spring constant meets the Jacobians of the last one (they read the masses, the laws'
slopes and the vanishing step, not the spring's force). Counted, never timed; the states
equal those made with every factorisation anew."""

from __future__ import annotations

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.implicit.initial_state import consistent_initial_state
from lumped.solvers.newton import linalg

try:
    from lumped.solvers.newton.linalg import kept_factor_solver
except ImportError:  # (the code before: nothing kept)
    kept_factor_solver = None

solve_anew = consistent_initial_state.__wrapped__  # (not the state kept per scene object)


def _released(k: float, x0: float = 0.3) -> Scene:
    """``viscous-soft`` of the bench (m = 1, k = 10, gamma = 0.2, tau = 0.5, x0 = 0.3)
    with a second, Coulomb, dashpot beside the Bingham one: both slip from rest, and with
    two forces left to one mass's balance the initial state takes Newton (one dashpot
    alone takes its yield force without Newton:
    :func:`lumped.solvers.implicit.initial_rest.initial_rest_forces`)."""
    return Scene(
        [Mass("mass", m=1.0, x0=x0)],
        [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=0.2, tau=0.5), "ground", "mass"),
         Element("friction", get_law("coulomb").bind(tau=0.25, r=10.0), "ground", "mass")],
    )


def _junction(k: float) -> Scene:
    """A spring on a mass, a Bingham dashpot from the mass to a junction and a newtonian
    one from the junction to ground: the junction's velocity is an unknown too."""
    return Scene(
        [Mass("mass", m=2.0, x0=0.4), Junction("j")],
        [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
         Element("slip", get_law("bingham").bind(gamma=0.5, tau=0.3), "j", "mass"),
         Element("drag", get_law("newtonian").bind(c=1.5), "ground", "j")],
    )


def test_a_new_spring_constant_factorises_no_jacobian(monkeypatch):
    solve_anew(_released(10.000111))
    calls = []
    real = linalg.lu_factor
    monkeypatch.setattr(linalg, "lu_factor", lambda J: calls.append(1) or real(J))
    v, F, stats = solve_anew(_released(10.000222))
    assert stats["newton_iterations"] > 0 and stats["factorizations"] > 0
    assert not calls


def test_kept_factors_give_the_states_of_factors_made_anew(monkeypatch):
    """Every state (velocities, forces and counters) is the one made with no factors kept,
    in whatever order the scenes come."""
    scenes = [_released(10.0 + 1e-4), _junction(7.0), _released(10.0 + 2e-4, x0=-0.2),
              _junction(7.5), _released(3.0, x0=1e-3), _released(10.0 + 3e-4)]
    anew = []
    for scene in scenes:
        linalg._KEPT.clear()
        anew.append(solve_anew(scene))
    for order in (scenes, scenes[::-1]):
        for scene in order:
            assert solve_anew(scene) == anew[scenes.index(scene)]


def test_a_jacobian_is_kept_by_its_bits():
    """A signed zero is not the other zero (the factors hold the entries, and a solve
    gives ``-0.0`` or ``0.0`` by them); equal bits give the kept solver."""
    J = [[1.0, 0.0], [2.0, 4.0]]
    got = kept_factor_solver(J)
    assert kept_factor_solver([[1.0, 0.0], [2.0, 4.0]]) is got
    assert kept_factor_solver([[1.0, -0.0], [2.0, 4.0]]) is not got
    assert got([1.0, 2.0]) == linalg.factor_solver(J)([1.0, 2.0])
    assert kept_factor_solver([[0.0, 0.0], [0.0, 1.0]]) is None  # singular: kept too
