"""What a :class:`~lumped.result.Solution` computes from its samples.

:mod:`.columns` (the scene's column layout, elongations and net nodal forces, vectorised
over samples), :mod:`.dense` (cubic Hermite dense output), :mod:`.switching` (the active
branch of every element per sample: switching events and stick intervals),
:mod:`.energy` (the energy ledger), :mod:`.frames` (relative and absolute motion on a
moving ground), and :mod:`.loops` (hysteresis loops, the energy per
cycle and equivalent damping of a periodic steady state).
"""

from .dense import hermite_dense
from .energy import EnergyLedger, energy_ledger
from .frames import Frame, GroundTrace, absolute_frame, ground_trace, relative_frame, support_traces
from .loops import Cycle, CycleReport, HysteresisLoop, cycles, hysteresis
from .switching import branch_history, lock_intervals, switch_events

__all__ = [
    "Cycle",
    "CycleReport",
    "EnergyLedger",
    "Frame",
    "GroundTrace",
    "HysteresisLoop",
    "absolute_frame",
    "branch_history",
    "cycles",
    "energy_ledger",
    "ground_trace",
    "hermite_dense",
    "hysteresis",
    "lock_intervals",
    "relative_frame",
    "support_traces",
    "switch_events",
]
