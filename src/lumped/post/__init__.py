"""What a :class:`~lumped.result.Solution` computes from its samples.

:mod:`.columns` (the scene's column layout, elongations and net nodal forces, vectorised
over samples), :mod:`.dense` (cubic Hermite dense output), :mod:`.switching` (the active
branch of every element per sample: switching events and stick intervals) and
:mod:`.energy` (the energy ledger).
"""

from .dense import hermite_dense
from .energy import EnergyLedger, energy_ledger
from .switching import branch_history, lock_intervals, switch_events

__all__ = [
    "EnergyLedger",
    "branch_history",
    "energy_ledger",
    "hermite_dense",
    "lock_intervals",
    "switch_events",
]
