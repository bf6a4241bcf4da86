"""Newton: the small nonlinear systems of one step and their linear algebra.

The bottom layer of the solvers; it imports nothing from the other solver sub-packages.
:mod:`.semismooth` (:func:`~.semismooth.newton_solve`, the semismooth Newton iteration),
:mod:`.options` (its options, result and codes), :mod:`.criteria` (the convergence tests),
:mod:`.min_norm` (minimum-norm steps of a rank-deficient Jacobian), :mod:`.linalg` (small
LU on Python floats, the factor cache), :mod:`.scalar_root` (one law's root in ``F``);
the compiled twins :mod:`.semismooth_jit`, :mod:`.criteria_jit`, :mod:`.linalg_jit`.
"""
