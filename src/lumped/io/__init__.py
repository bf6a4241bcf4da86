"""Input and output: scene files (TOML, :mod:`.scenefile`) and tabulated inputs (CSV and
PEER ``.AT2`` records, :mod:`.tables`; the :class:`Table` type, :mod:`.tabulated`; units,
:mod:`.units`)."""

from .scenefile import (
    SETTINGS_KEYS,
    SceneFileError,
    load_scene,
    read_scene_file,
    scene_from_dict,
)
from .tables import TableError, read_at2, read_table
from .tabulated import Table, detrend

__all__ = ["SETTINGS_KEYS", "SceneFileError", "Table", "TableError", "detrend", "load_scene",
           "read_at2", "read_scene_file", "read_table", "scene_from_dict"]
