"""Work-precision benchmark against the exact reference and scipy (``lumped bench``).

:mod:`.scenes` (what is run), :mod:`.methods` (our methods, and
:func:`tolerance_method` for any ``simulate`` method driven by ``rtol``/``atol``),
:mod:`.peers` (scipy on the tanh-regularised model), :mod:`.event_peer` (scipy on the
exact law with terminal events), :mod:`.runner` (timing, runs, the method registry
:func:`register_bench_method`), :mod:`.report` (tables, CSV, plot), :mod:`.event_study`
and :mod:`.new_numbers` (scenes with numbers never run before: the user's columns); the
full description is in :mod:`.runner`.
"""

from .event_peer import MAX_EVENTS, event_driven_solver
from .event_study import EVENT_SCENES, event_markdown, event_study
from .methods import Method, Solved, tolerance_method, x_on_grid
from .new_numbers import bench_scene_with_new_numbers, new_factor, scene_with_new_numbers
from .peers import regularised_jacobian, regularised_rhs
from .report import (
    markdown_tables,
    new_numbers_tables,
    observed_orders,
    ratio_table,
    read_csv,
    summarize_runs,
    write_csv,
    write_markdown,
    write_outputs,
    write_plot,
)
from .runner import (
    BENCH_METHODS,
    KINDS,
    METHODS,
    BenchReport,
    RunResult,
    available_methods,
    count_steps,
    creep_table,
    register_bench_method,
    run_benchmark,
    run_one,
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
from .timing import measure_unit, time_call, yardstick

__all__ = [
    "BENCH_METHODS",
    "BenchReport",
    "BenchScene",
    "EVENT_SCENES",
    "FULL",
    "GRID_DT",
    "KINDS",
    "Ladders",
    "MAX_EVENTS",
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
    "bench_scene_with_new_numbers",
    "check_ladders",
    "count_steps",
    "creep_table",
    "event_driven_solver",
    "event_markdown",
    "event_study",
    "generic_scene",
    "markdown_tables",
    "measure_unit",
    "new_factor",
    "new_numbers_tables",
    "observed_orders",
    "ratio_table",
    "read_csv",
    "reference_grid",
    "register_bench_method",
    "regularised_jacobian",
    "regularised_rhs",
    "run_benchmark",
    "run_one",
    "scene_with_new_numbers",
    "summarize_runs",
    "time_call",
    "tolerance_method",
    "write_csv",
    "write_markdown",
    "write_outputs",
    "write_plot",
    "x_on_grid",
    "yardstick",
]
