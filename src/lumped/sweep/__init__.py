"""Parameter studies: run a family of scenes and tabulate what each did.

:func:`simulate_many` takes a template (a scene file, its dict, or a builder) and a grid
or list of parameter sets, runs every scene -- batched and compiled for the paper's
oscillator, per scene otherwise, locally or on Dask -- and returns a
:class:`SweepResult` whose ``table`` has one row per scene. See ``docs/sweeps.md``.
"""

from .params import ParameterSets, parameter_sets, parse_grid_spec
from .result import SweepResult
from .run import BACKENDS, simulate_many
from .summary import QUANTITIES

__all__ = [
    "BACKENDS",
    "QUANTITIES",
    "ParameterSets",
    "SweepResult",
    "parameter_sets",
    "parse_grid_spec",
    "simulate_many",
]
