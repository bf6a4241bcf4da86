"""Radau IIA of order 5: one step of the 3-stage method on a scene's DAE, a mode held.

:mod:`.tableau` (nodes, Butcher matrix, error and dense-output weights), :mod:`.stage`
(the stage system and its Newton; compiled: :mod:`.stage_jit`), :mod:`.roundoff` (its test
of a junction's velocity at the round-off of its laws), :mod:`.error` (the error
estimate and its norm), :mod:`.cone_split` (the force split among locks in parallel in
the stage solve), :mod:`.dense` and :mod:`.rows` (the dense output and the output rows),
:mod:`.dense_defect` (the dense output against the held laws after an event) and
:mod:`.step_jit` (a step's compiled pieces for the compiled loop).
"""
