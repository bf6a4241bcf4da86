"""Work-precision benchmark against the exact reference and scipy (``lumped bench``).

:mod:`.scenes` (what is run), :mod:`.methods` (our methods), :mod:`.peers` (scipy),
:mod:`.runner` (timing, runs, the method registry), :mod:`.report` (tables, CSV, plot)
and :mod:`.event_study`; the full description is in :mod:`.runner`.
"""

from .event_study import (
    EVENT_SCENES,
    event_markdown,
    event_study,
)
from .methods import (
    Method,
    Solved,
)
from .peers import (
    regularised_jacobian,
    regularised_rhs,
)
from .report import (
    markdown_tables,
    observed_orders,
    read_csv,
    summarize_runs,
    write_csv,
    write_markdown,
    write_outputs,
    write_plot,
)
from .runner import (
    METHODS,
    BenchReport,
    RunResult,
    available_methods,
    creep_table,
    measure_unit,
    run_benchmark,
    run_one,
    time_call,
    yardstick,
)
from .scenes import (
    FULL,
    GRID_DT,
    OWN_SCENES,
    PAPER_SCENES,
    QUICK,
    SCENES,
    TARGETS,
    YARDSTICK_ITERATIONS,
    BenchScene,
    Ladders,
    check_ladders,
    generic_scene,
    reference_grid,
)

__all__ = [
    "BenchReport",
    "BenchScene",
    "EVENT_SCENES",
    "FULL",
    "GRID_DT",
    "Ladders",
    "METHODS",
    "Method",
    "OWN_SCENES",
    "PAPER_SCENES",
    "QUICK",
    "RunResult",
    "SCENES",
    "Solved",
    "TARGETS",
    "YARDSTICK_ITERATIONS",
    "available_methods",
    "check_ladders",
    "creep_table",
    "event_markdown",
    "event_study",
    "generic_scene",
    "markdown_tables",
    "measure_unit",
    "observed_orders",
    "read_csv",
    "reference_grid",
    "regularised_jacobian",
    "regularised_rhs",
    "run_benchmark",
    "run_one",
    "summarize_runs",
    "time_call",
    "write_csv",
    "write_markdown",
    "write_outputs",
    "write_plot",
    "yardstick",
]
