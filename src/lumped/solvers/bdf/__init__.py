"""The generic fixed-step BDF1/BDF2 methods: ``bdf1``, ``bdf2``, ``jit-bdf1``, ``jit-bdf2``.

:mod:`.fixed_step` (:func:`~.fixed_step.run_bdf`, the readable reference),
:mod:`.impact_step` (a fixed step across an impact), :mod:`.fixed_step_jit` (the compiled
run: :mod:`.core_jit`, the step loop compiled once for every scene; :mod:`.fast_codegen`
and :mod:`.fast_jit`, the fast loop generated per scene and its hand-over) and
:mod:`.runners` (the methods for the registry).
"""
