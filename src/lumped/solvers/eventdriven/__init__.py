"""The event-driven adaptive method ``radau5``: the driver over Radau IIA steps.

:mod:`.runner` (:func:`~.runner.run_radau5`, the entry point), :mod:`.setup` (keywords,
forcing breakpoints, the per-scene plan), :mod:`.run` (one run's state and loop),
:mod:`.step` (one pass of the Python loop), :mod:`.checks` (what a solved step is checked
for), :mod:`.mode_state` (the run's mode and what happens at an event: where ``radau5`` chooses
a mode after an event), :mod:`.landing` (the landing on a guard's root), :mod:`.bridge`
(backward Euler over a stop), :mod:`.fast` and :mod:`.loop_jit` (the compiled loop of
held-mode steps and its bridge to the driver).
"""
