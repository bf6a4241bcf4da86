"""The result of a sweep: one tidy table, its grid view, files and a heat map."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SweepResult"]


@dataclass
class SweepResult:
    """What :func:`lumped.sweep.simulate_many` returns.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per scene, in the order of the parameter sets (for a grid: row-major,
        the last path varying fastest): the parameter columns (their dotted paths), then
        the quantities of :mod:`lumped.sweep.summary`.
    parameters : tuple of str
        The parameter columns.
    grid : dict of str to numpy.ndarray, or None
        The axes of a grid sweep (``None`` for a list of parameter sets).
    trajectories : list of Solution, or None
        The full solutions, in row order, when ``keep_trajectories=True``.
    backend : str
        What ran the scenes: ``"compiled"`` (batched closed form in this process),
        ``"processes"``, ``"serial"`` or ``"dask"`` (with the path, e.g.
        ``"dask/compiled"``).
    """

    table: Any
    parameters: tuple[str, ...]
    grid: dict[str, np.ndarray] | None
    trajectories: list | None = None
    backend: str = ""

    def __len__(self) -> int:
        return len(self.table)

    @property
    def ok(self) -> bool:
        """Whether every scene ran to the end."""
        return bool((self.table["status"] == "success").all())

    def column_for(self, quantity: str) -> str:
        """The table column a quantity name stands for.

        A column name is returned as is; a per-node quantity without its node
        (``"rest_position"``) is accepted when the scene has one node.
        """
        cols = list(self.table.columns)
        if quantity in cols:
            return quantity
        matches = [c for c in cols if c.startswith(f"{quantity}.")]
        if len(matches) == 1:
            return matches[0]
        numeric = [c for c in cols if c not in self.parameters
                   and c not in ("status", "message", "method")]
        if matches:
            raise ValueError(f"`quantity` {quantity!r} is ambiguous: one of {matches}")
        raise ValueError(f"`quantity` must be one of {numeric}, got {quantity!r}")

    def to_xarray(self):
        """An :class:`xarray.Dataset`: over the grid's axes for a grid, else over ``scene``.

        Missing values (``rest_position`` of a scene still moving at the end) become NaN
        here, masked by the ``at_rest`` variable.
        """
        import xarray as xr

        frame = self.table.copy()
        for col in frame.columns:
            if str(frame[col].dtype) == "Float64":
                frame[col] = frame[col].astype(float)
        if self.grid is None:
            return xr.Dataset.from_dataframe(frame.rename_axis("scene"))
        dims = list(self.grid)
        ds = xr.Dataset.from_dataframe(frame.set_index(dims))
        return ds.assign_coords({d: np.asarray(self.grid[d]) for d in dims})

    def write(self, out: str | Path, *, stem: str = "sweep") -> list[Path]:
        """Write the table into ``out``: ``<stem>.csv``, and ``<stem>.nc`` with xarray and
        ``<stem>.parquet`` with pyarrow (both in the ``sweep`` and ``test`` extras).

        The CSV has full (round-trip) precision; a missing value is an empty cell. The
        NetCDF file is :meth:`to_xarray` written by xarray's ``scipy`` engine (NetCDF3
        classic, readable by every NetCDF library; no extra dependency): the grid's axes
        are its dimensions (``scene`` for a list of parameter sets), strings (``status``,
        ``message``, ``method``) are stored as UTF-8 character arrays, counters as 32-bit
        integers (NetCDF3 has no 64-bit integer), booleans as bytes that xarray reads back
        as booleans, a missing ``rest_position`` as NaN (masked by ``at_rest``). The global
        attributes ``parameters`` (comma-separated) and ``backend`` say how it was made.
        Returns the paths written.
        """
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        csv = out / f"{stem}.csv"
        self.table.to_csv(csv, index=False, float_format="%.17g")
        written = [csv]
        try:
            import xarray  # noqa: F401
        except ImportError:  # the `sweep` extra brings it
            pass
        else:
            written.append(self.write_netcdf(out / f"{stem}.nc"))
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            return written
        parquet = out / f"{stem}.parquet"
        self.table.to_parquet(parquet, index=False)
        written.append(parquet)
        return written

    def write_netcdf(self, path: str | Path) -> Path:
        """Write :meth:`to_xarray` to ``path`` as NetCDF3 (xarray's ``scipy`` engine; see
        :meth:`write`) and return the path. Read it back with
        ``xarray.open_dataset(path)``."""
        ds = self.to_xarray()
        ds.attrs["parameters"] = ", ".join(self.parameters)
        ds.attrs["backend"] = self.backend
        ds.attrs["source"] = "lumped.sweep.simulate_many"
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(path, engine="scipy", format="NETCDF3_64BIT")
        return path

    def heatmap(self, quantity: str, path: str | Path, *, title: str | None = None) -> Path:
        """Plot ``quantity`` over a grid of one axis (a line) or two (a heat map) to ``path``.

        Cells without a value (not at rest, or a failed scene) are left blank (grey), and
        failed scenes are crossed. Needs matplotlib.
        """
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        col = self.column_for(quantity)
        if self.grid is None or len(self.grid) not in (1, 2):
            raise ValueError("a heat map needs a grid sweep of one or two parameters, got "
                             f"{'a list' if self.grid is None else len(self.grid)}")
        values = np.asarray(self.table[col].astype(float), dtype=float)
        failed = np.asarray(self.table["status"] != "success")
        dims = list(self.grid)
        fig, ax = plt.subplots(figsize=(6.0, 4.5), layout="constrained")
        if len(dims) == 1:
            xs = np.asarray(self.grid[dims[0]], dtype=float)
            ax.plot(xs, values, ".-")
            ax.plot(xs[failed], np.zeros(failed.sum()), "rx", label="failed")
            ax.set_xlabel(dims[0])
            ax.set_ylabel(col)
        else:
            ys = np.asarray(self.grid[dims[0]], dtype=float)
            xs = np.asarray(self.grid[dims[1]], dtype=float)
            grid = np.ma.masked_invalid(values.reshape(len(ys), len(xs)))
            cmap = plt.get_cmap("viridis").with_extremes(bad="0.85")
            mesh = ax.pcolormesh(xs, ys, grid, shading="nearest", cmap=cmap)
            fig.colorbar(mesh, ax=ax, label=col)
            bad = failed.reshape(len(ys), len(xs))
            if bad.any():
                yy, xx = np.nonzero(bad)
                ax.plot(xs[xx], ys[yy], "rx", ms=4, label="failed")
            ax.set_xlabel(dims[1])
            ax.set_ylabel(dims[0])
        if failed.any():
            ax.legend(loc="best", fontsize=8)
        ax.set_title(title or col, fontsize=10)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
        plt.close(fig)
        return path
