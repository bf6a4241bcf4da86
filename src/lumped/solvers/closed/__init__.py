"""The closed form for the paper's oscillator (one mass, a linear spring and a Bingham
dashpot): Algorithm 1 and its BDF2 twin.

:mod:`.closed_form` (the steps, the sign relation (16), the Python loops),
:mod:`.closed_form_jit` (their compiled twin and batched summaries), :mod:`.integrate`
(runs either over a grid) and :mod:`.runners` (``closed-bdf1``, ``closed-bdf2`` and
``exact`` for the registry).
"""
