"""The one result type of :func:`lumped.simulate`: :class:`Solution`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .solvers.status import Event, Status

__all__ = ["Solution"]


@dataclass(frozen=True)
class Solution:
    """The result of :func:`simulate`.

    Attributes
    ----------
    columns : tuple of str
        ``t``, then ``x_<node>``, ``v_<node>`` per node, then ``F_<element>`` per element.
    data : numpy.ndarray
        ``(n_samples, len(columns))`` array; row 0 is the consistent initial state.
    node_names, element_names : tuple of str
    method : str
        The method that ran (``auto`` resolved).
    stats : dict
        ``steps``, ``newton_iterations``, ``residual_evals``, ``jacobian_evals``,
        ``factorizations`` (zero for the closed form), ``max_newton_iterations``.
    status : Status
    message : str
        Empty on success; otherwise what failed, when and where.
    events : tuple of Event
        Switching events, impacts and time events the method located (empty when the
        method does not report them).
    indeterminate : dict
        Element name -> intervals ``(t0, t1)`` on which its force is not unique.
    """

    columns: tuple[str, ...]
    data: np.ndarray
    node_names: tuple[str, ...]
    element_names: tuple[str, ...]
    method: str
    stats: dict = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""
    events: tuple[Event, ...] = ()
    indeterminate: dict[str, list[tuple[float, float]]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.data.ndim != 2 or self.data.shape[1] != len(self.columns):
            raise ValueError(
                f"`data` has shape {self.data.shape}, expected (n, {len(self.columns)})"
            )
        if not np.all(np.isfinite(self.data)):
            r, c = np.argwhere(~np.isfinite(self.data))[0]
            raise FloatingPointError(
                f"non-finite {self.columns[c]} = {self.data[r, c]!r} at row {r}"
            )

    def column(self, name: str) -> np.ndarray:
        """One column by name, e.g. ``"x_mass"``."""
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column {name!r}; columns are {self.columns}") from None

    @property
    def t(self) -> np.ndarray:
        return self.data[:, 0]

    @property
    def x(self) -> dict[str, np.ndarray]:
        """Displacement per node."""
        return {n: self.column(f"x_{n}") for n in self.node_names}

    @property
    def v(self) -> dict[str, np.ndarray]:
        """Velocity per node."""
        return {n: self.column(f"v_{n}") for n in self.node_names}

    @property
    def F(self) -> dict[str, np.ndarray]:
        """Force per element (positive in tension)."""
        return {e: self.column(f"F_{e}") for e in self.element_names}

    @property
    def forces(self) -> np.ndarray:
        """``(n_samples, n_elements)`` array of the element forces."""
        return self.data[:, 1 + 2 * len(self.node_names):]

    @property
    def ok(self) -> bool:
        return self.status is Status.SUCCESS

    def to_csv(self, path: str | Path) -> Path:
        """Write the columns with a header line, ``%.17g`` (round-trip precision)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(path, self.data, fmt="%.17g", delimiter=",",
                   header=",".join(self.columns), comments="")
        return path
