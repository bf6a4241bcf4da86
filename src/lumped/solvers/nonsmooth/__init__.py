"""Nonsmooth mechanics: impacts, locks and the forces the motion does not fix.

:mod:`.impacts` (which elements lock, the impulse, the energy lost), :mod:`.locks`
(force-free elements in parallel, intervals of indeterminate forces, the minimum-norm
split of free forces), :mod:`.lock_forces` (forces of locked and stuck elements from the
balance of accelerations), :mod:`.rest_balance` (the static balance at rest),
:mod:`.junction_balance` (massless junctions at ``t = 0``) and :mod:`.groups` (connected
groups of nodes). Imports only :mod:`lumped.solvers.newton` below it.
"""
