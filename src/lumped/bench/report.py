r"""Summaries and output of a benchmark: best time per target, observed orders, CSV,
Markdown tables and the work-precision plot.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path

from .event_study import event_markdown, slope_above_floor
from .runner import BENCH_METHODS, BenchReport, RunResult
from .scenes import FULL, GRID_DT, TARGETS, YARDSTICK_ITERATIONS

__all__ = [
    "summarize_runs",
    "observed_orders",
    "write_csv",
    "read_csv",
    "markdown_tables",
    "ratio_table",
    "new_numbers_tables",
    "write_markdown",
    "write_plot",
    "write_outputs",
]

# --------------------------------------------------------------------------- summary


def summarize_runs(
    runs: Sequence[RunResult], targets: Sequence[float] = TARGETS, *,
    new_numbers: bool = False,
) -> dict[tuple[str, float, str], RunResult | None]:
    """For each ``(scene, target, method)`` the fastest ok run with ``max_err <= target``.

    ``None`` means no run of that method reached the target ("unreachable").
    ``new_numbers=True``: the user's view, only the runs timed with new numbers, the
    fastest by ``cpu_new_s`` (the methods without that column are left out).
    """
    out: dict[tuple[str, float, str], RunResult | None] = {}
    for r in runs:
        if new_numbers and not r.has_new_numbers:
            continue
        for tgt in targets:
            key = (r.scene, tgt, r.method)
            out.setdefault(key, None)
            if r.ok and r.max_err <= tgt:
                best = out[key]
                if best is None or _time(r, new_numbers) < _time(best, new_numbers):
                    out[key] = r
    return out


def _time(r: RunResult, new_numbers: bool) -> float:
    return r.cpu_new_s if new_numbers else r.cpu_s


def observed_orders(
    runs: Sequence[RunResult], *, floor: float = 1e-13, max_dt: float = 1e-4,
) -> dict[tuple[str, str], tuple[float, float, str]]:
    """Least-squares slope of ``log err`` against ``log dt`` for each ``(scene, method)``.

    Returns ``(order in max_err, order in end_err, dt range)`` for the time-stepping
    methods, fitted on the runs with ``dt <= max_dt`` (the asymptotic range: coarser
    steps stop the mass after a different number of swings), or on the three finest
    runs when fewer than three have ``dt <= max_dt`` (the slow generic solver's ladder
    stops at ``Ladders.slow_min_dt``).  Errors below ``floor`` (round-off, or an exactly
    reproduced rest) are left out; a slope needs three points (``nan`` otherwise).
    """
    groups: dict[tuple[str, str], list[RunResult]] = {}
    for r in runs:
        if r.ok and math.isfinite(r.dt):
            groups.setdefault((r.scene, r.method), []).append(r)
    out = {}
    for key, rows in groups.items():
        rows = sorted(rows, key=lambda r: r.dt)
        fine = [r for r in rows if r.dt <= max_dt * (1 + 1e-12)]
        if len(fine) < 3:
            fine = rows[:3]
        span = f"{fine[0].dt:g}..{fine[-1].dt:g}"
        out[key] = (slope_above_floor([(r.dt, r.max_err) for r in fine], floor),
                    slope_above_floor([(r.dt, r.end_err) for r in fine], floor), span)
    return out


# --------------------------------------------------------------------------- output


def print_and_save(text: str, out: str | Path | None) -> None:
    """Print a benchmark script's report and, when ``out`` is given, write it there."""
    print(text)
    if out:
        Path(out).write_text(text + "\n")


def write_csv(runs: Sequence[RunResult], path: str | Path) -> Path:
    """All runs, one row each, full precision."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names = [f.name for f in fields(RunResult)]
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for r in runs:
            w.writerow([_csv_cell(getattr(r, n)) for n in names])
    return path


def read_csv(path: str | Path) -> list[RunResult]:
    """The runs written by :func:`write_csv` (to redraw tables or plots)."""
    kinds = {f.name: f.type for f in fields(RunResult)}
    out = []
    with Path(path).open(newline="") as fh:
        for row in csv.DictReader(fh):
            out.append(RunResult(**{
                k: (int(v) if kinds[k] in ("int", int) else
                    float(v) if kinds[k] in ("float", float) else v)
                for k, v in row.items()}))
    return out


def _csv_cell(value: object) -> object:
    if isinstance(value, float):
        return repr(value)
    return value


def _cell(r: RunResult | None) -> str:
    if r is None:
        return "unreachable"
    return f"{r.ratio:.3g} ({r.setting})"


def markdown_tables(report: BenchReport, targets: Sequence[float] = TARGETS) -> str:
    """The summary (per scene and target) and the creep table as markdown."""
    best = summarize_runs(report.runs, targets)
    methods = report.methods
    lines = [
        f"Time unit: the yardstick ({YARDSTICK_ITERATIONS} iterations of a pure-Python "
        f"symplectic Euler loop) took {report.unit_s * 1e3:.2f} ms of CPU time in this run. "
        "Each cell: fastest run reaching the target in max |x - x_ref| on [0, 5], "
        "as CPU time / yardstick (setting).",
        "",
    ]
    ours = _ours(report)
    for scene in report.scenes:
        lines.append(f"#### {scene}")
        lines.append("")
        lines.append("| target | " + " | ".join(methods) + " | best ours / fastest scipy |")
        lines.append("|---" * (len(methods) + 2) + "|")
        for tgt in targets:
            cells = [_cell(best.get((scene, tgt, m))) for m in methods]
            lines.append(f"| {tgt:g} | " + " | ".join(cells) + f" | "
                         f"{_ours_vs_scipy(best, scene, tgt, methods, ours)} |")
        lines.append("")
    lines += _overall_table(report, best, targets, ours)
    lines += ["#### Our best method / the fastest scipy peer", "",
              "CPU time of our fastest run that reaches the target over the fastest scipy run "
              "(tanh-regularised or event-driven) that does; below 1: we are faster.", "",
              ratio_table(report, targets)]
    lines += new_numbers_tables(report, targets)
    if report.reference_s:
        lines.append("For comparison, the exact event-driven reference on the same "
                     f"{GRID_DT:g} grid (error at round-off level) took, in yardstick units: "
                     + ", ".join(f"{k} {v / report.unit_s:.3g}"
                                 for k, v in report.reference_s.items()) + ".")
        lines.append("")
    failed = [r for r in report.runs if not r.ok]
    lines.append(f"Failed runs: {len(failed)} of {len(report.runs)}"
                 + (" (listed in the CSV with their messages)." if failed else "."))
    by_method: dict[str, int] = {}
    for r in failed:
        by_method[r.method] = by_method.get(r.method, 0) + 1
    if by_method:
        lines.append("By method: " + ", ".join(f"{k}: {v}" for k, v in sorted(by_method.items()))
                     + ".")
    lines.append("")
    if report.creep:
        lines.append(f"#### Creep: release-0.005 held for {FULL.creep_t_end:g} s "
                     "(exact drift: 0)")
        lines.append("")
        lines.append("| method | setting | max abs(x - 0.005) | x(end) | status |")
        lines.append("|---|---|---|---|---|")
        for c in report.creep:
            lines.append(f"| {c['method']} | {c['setting']} | {c['drift']:.3g} | "
                         f"{c['x_end']:.10g} | {c['status']} |")
        lines.append("")
    return "\n".join(lines)


def _ours(report: BenchReport) -> set[str]:
    """The names of our methods in ``report`` (older reports: from the registry)."""
    if report.ours:
        return set(report.ours)
    return {m.name for m in BENCH_METHODS.values() if m.ours}


def ratio_table(report: BenchReport, targets: Sequence[float] = TARGETS, *,
                new_numbers: bool = False) -> str:
    """Per scene and target: our best method's time over the fastest scipy time.

    The scipy side is the fastest of every peer (tanh-regularised or event-driven) that
    reached the target; a ratio below 1 means we are faster. Each cell names the two
    runs compared. ``new_numbers=True``: our side is the user's view, the fastest run
    with new numbers (``cpu_new_s``) of the methods that have that column; each cell
    adds that run's time with new numbers over its warm repeat.
    """
    best = summarize_runs(report.runs, targets)
    ours = _ours(report)
    mine = [m for m in report.methods if m in ours]
    peers = [m for m in report.methods if m not in ours]
    if new_numbers:
        return _new_numbers_ratio_table(report, targets, best, mine, peers)
    lines = ["| scene | " + " | ".join(f"{t:g}" for t in targets) + " |",
             "|---" * (len(targets) + 1) + "|"]
    for scene in report.scenes:
        cells = []
        for tgt in targets:
            a = _fastest(best, scene, tgt, mine)
            b = _fastest(best, scene, tgt, peers)
            if a is None or b is None:
                cells.append("-" if a is None and b is None else
                             "ours unreachable" if a is None else "scipy unreachable")
            else:
                cells.append(f"{a.cpu_s / b.cpu_s:.3g} ({a.method} / {b.method})")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _new_numbers_ratio_table(report, targets, best, mine, peers) -> str:
    fresh = summarize_runs(report.runs, targets, new_numbers=True)
    lines = ["| scene | " + " | ".join(f"{t:g}" for t in targets) + " |",
             "|---" * (len(targets) + 1) + "|"]
    for scene in report.scenes:
        cells = []
        for tgt in targets:
            a = _fastest(fresh, scene, tgt, mine, new_numbers=True)
            b = _fastest(best, scene, tgt, peers)
            if a is None or b is None:
                cells.append("-" if a is None and b is None else
                             "ours unreachable" if a is None else "scipy unreachable")
            else:
                cells.append(f"{a.cpu_new_s / b.cpu_s:.3g} ({a.method} / {b.method}; "
                             f"new/warm {a.new_over_warm:.3g})")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def new_numbers_tables(report: BenchReport, targets: Sequence[float] = TARGETS) -> list[str]:
    """The user's columns as markdown lines: per scene and target, each method's fastest
    run with new numbers and its ratio to the warm repeat, then our best with new numbers
    over the fastest scipy peer. No lines when no run has that column."""
    names = [m for m in report.methods
             if any(r.method == m and r.has_new_numbers for r in report.runs)]
    if not names:
        return []
    fresh = summarize_runs(report.runs, targets, new_numbers=True)
    lines = ["#### With new numbers (the user's columns)", "",
             "Each setting of these methods ran again after its warm timing, with new "
             "numbers: the scene's k times 1 + 1e-6 (n + r) (never run before), a new k "
             "and a new scene object no other run touched for each run, no warm-up: what "
             "a user who edits a number gets. As many such runs as the warm timing took "
             "calls (at most 20), the smallest time kept (the warm time's statistic; "
             "`cpu_new_first_s` in runs.csv is the first run alone). Each cell: the "
             "fastest setting reaching the target (its error is the warm run's), as CPU "
             "time / yardstick (setting; its time with new numbers / its warm time).", "",
             "| scene | target | " + " | ".join(names) + " |",
             "|---" * (len(names) + 2) + "|"]
    for scene in report.scenes:
        for tgt in targets:
            cells = []
            for m in names:
                r = fresh.get((scene, tgt, m))
                cells.append("unreachable" if r is None else
                             f"{r.ratio_new:.3g} ({r.setting}; {r.new_over_warm:.3g}x)")
            lines.append(f"| {scene} | {tgt:g} | " + " | ".join(cells) + " |")
    lines += ["", "Our best method with new numbers / the fastest scipy peer (the peers "
              "compile nothing per scene: their warm time):", "",
              ratio_table(report, targets, new_numbers=True)]
    return lines


def _fastest(best, scene, tgt, names, *, new_numbers: bool = False) -> RunResult | None:
    cands = [best.get((scene, tgt, m)) for m in names]
    cands = [c for c in cands if c is not None]
    return min(cands, key=lambda r: _time(r, new_numbers)) if cands else None


def _ours_vs_scipy(best, scene, tgt, methods, ours) -> str:
    a = _fastest(best, scene, tgt, [m for m in methods if m in ours])
    b = _fastest(best, scene, tgt, [m for m in methods if m not in ours])
    if a is None and b is None:
        return "-"
    if a is None:
        return "ours unreachable"
    if b is None:
        return "scipy unreachable"
    return f"{a.cpu_s / b.cpu_s:.3g}"


def _overall_table(report, best, targets, ours) -> list[str]:
    """Per target and method: scenes reached, and the geometric mean of the fastest ratios."""
    lines = ["#### All scenes", "",
             "Per target and method: scenes where the target was reached, and the geometric "
             "mean over those scenes of the fastest time (yardstick units).", "",
             "| target | " + " | ".join(report.methods) + " |",
             "|---" * (len(report.methods) + 1) + "|"]
    n = len(report.scenes)
    for tgt in targets:
        cells = []
        for m in report.methods:
            got = [best.get((s, tgt, m)) for s in report.scenes]
            got = [g for g in got if g is not None]
            if not got:
                cells.append(f"0/{n}")
                continue
            gm = math.exp(sum(math.log(max(g.ratio, 1e-12)) for g in got) / len(got))
            cells.append(f"{len(got)}/{n}, {gm:.3g}")
        lines.append(f"| {tgt:g} | " + " | ".join(cells) + " |")
    lines.append("")
    return lines


def write_markdown(report: BenchReport, path: str | Path) -> Path:
    """``markdown_tables`` plus the orders of the step methods, written to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    orders = observed_orders(report.runs)
    lines = [markdown_tables(report),
             "#### Observed orders (slope of log error vs log dt)", "",
             "Fitted for dt <= 1e-4, or on the three finest dt of a shorter ladder.", "",
             "| scene | method | dt fitted | order, max over [0, 5] | order, x(5) |",
             "|---|---|---|---|---|"]
    for (scene, method), (p_max, p_end, span) in sorted(orders.items()):
        lines.append(f"| {scene} | {method} | {span} | {_order(p_max)} | {_order(p_end)} |")
    lines.append("")
    if report.events:
        lines += ["#### Orders between events (closed forms, errors at the nodes)", "",
                  event_markdown(report.events)]
    path.write_text("\n".join(lines))
    return path


def _order(p: float) -> str:
    return "n/a (errors < 1e-13: exact)" if not math.isfinite(p) else f"{p:.2f}"


def write_plot(report: BenchReport, path: str | Path) -> str:
    """Log-log error against time, one panel per scene and one line per method.

    Each line is the method's lower-left envelope (runs not beaten in both time and
    error by another run of the same method).  Returns a one-line notice.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        return "matplotlib is not installed: no plot written"
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = len(report.scenes)
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(9, 2.4 * rows), squeeze=False)
    markers = "os^vDP*Xh<>p"
    ours = _ours(report)
    for ax, scene in zip(axes.flat, report.scenes, strict=False):
        for i, m in enumerate(report.methods):
            pts = sorted((r.ratio, max(r.max_err, 1e-17)) for r in report.runs
                         if r.scene == scene and r.method == m and r.ok)
            front, best_err = [], math.inf
            for t, e in pts:
                if e < best_err:
                    front.append((t, e))
                    best_err = e
            if front:
                ax.loglog(*zip(*front, strict=True), marker=markers[i % len(markers)],
                          ms=3, lw=1, ls="-" if m in ours else "--", label=m,
                          color=plt.cm.tab20(i % 20))
        for tgt in TARGETS:
            ax.axhline(tgt, color="0.85", lw=0.5, zorder=0)
        ax.set_title(scene, fontsize=9)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("CPU time / yardstick", fontsize=8)
    for ax in axes[:, 0]:
        ax.set_ylabel("max |x - x_ref|", fontsize=8)
    # one legend entry per method over every panel (a method may have no run on a scene);
    # a method keeps its colour and marker in every panel
    legend: dict[str, object] = {}
    for ax in axes.flat:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, handle)
    labels = [m for m in report.methods if m in legend]
    handles = [legend[m] for m in labels]
    ncol = max(1, min(len(labels), 5))
    fig.legend(handles, labels, loc="lower center", ncol=ncol, fontsize=8)
    fig.tight_layout(rect=(0, 0.025 * math.ceil(len(labels) / ncol) + 0.01, 1, 1))
    fig.savefig(path, dpi=70)
    plt.close(fig)
    return f"plot written to {path}"


def write_outputs(report: BenchReport, out: str | Path) -> list[str]:
    """Write ``runs.csv``, ``summary.md`` and ``work_precision.png`` into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    msgs = [f"runs written to {write_csv(report.runs, out / 'runs.csv')}",
            f"summary written to {write_markdown(report, out / 'summary.md')}"]
    msgs.append(write_plot(report, out / "work_precision.png"))
    return msgs
