"""The implicit step: the discrete system of one BDF step and how it is solved.

:mod:`.step_system` (the residual and Jacobian of one step), :mod:`.branch_check` (the
fold test of a non-monotone law; compiled: :mod:`.branch_check_jit`), :mod:`.globalize`
(the globalised Newton of a hard step), :mod:`.force_projection` (nonlinear elimination of
forces by their laws), :mod:`.balance_sweeps`, and the consistent initial state
(:mod:`.initial_state`, :mod:`.initial_rest`, :mod:`.initial_slip`,
:mod:`.initial_user_forces`).
"""
