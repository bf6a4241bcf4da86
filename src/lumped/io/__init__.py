"""Input and output: scene files (TOML, :mod:`.scenefile`)."""

from .scenefile import SETTINGS_KEYS, SceneFileError, load_scene, read_scene_file, scene_from_dict

__all__ = ["SETTINGS_KEYS", "SceneFileError", "load_scene", "read_scene_file",
           "scene_from_dict"]
