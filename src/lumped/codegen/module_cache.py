r"""The disk cache of generated modules: where it lives, writing a module once, importing it.

Directory: ``$LUMPED_CACHE_DIR``, else ``$XDG_CACHE_HOME/lumped``, else
``~/.cache/lumped``; modules in ``jit/``, each named by a hash of its source. Files are
written to a temporary name and hard-linked into place (atomic, and it never replaces
a file another process wrote first; :func:`os.replace` where the file system has no
hard links), and never rewritten, so numba's cache index (keyed on the file's time
stamp) stays valid. A cache directory that cannot be written gives a warning and a
temporary directory (the code is compiled, not kept).

The modules themselves are made by :mod:`lumped.codegen.jit` (a scene's) and
:mod:`lumped.solvers.bdf.fast_codegen` (a scene's unrolled fixed-step loop).
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
import threading
import warnings
from pathlib import Path
from types import ModuleType

__all__ = ["LOADED_MODULES", "MODULE_LOCK", "cache_dir", "generated_module_exists",
           "import_generated", "loaded_key", "module_cached", "module_name"]


def cache_dir() -> Path:
    """The on-disk cache root (see the module notes); created on demand by the writers.
    (Read from the environment at every call, only the variables that decide it: each
    read of ``os.environ`` costs about a microsecond; the path is made once per value.)"""
    environ = os.environ
    env = environ.get("LUMPED_CACHE_DIR")
    if env:
        return _cache_dir(env, None, None)
    xdg = environ.get("XDG_CACHE_HOME")
    return _cache_dir(None, xdg, None if xdg else environ.get("HOME"))


@functools.lru_cache(maxsize=16)
def _cache_dir(env: str | None, xdg: str | None, home: str | None) -> Path:
    """:func:`cache_dir` for these values of ``LUMPED_CACHE_DIR``, ``XDG_CACHE_HOME`` and
    ``HOME`` (which :meth:`pathlib.Path.home` reads)."""
    if env:
        return Path(env)
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "lumped"


#: The generated modules imported in this process, by :func:`loaded_key`.
LOADED_MODULES: dict[tuple[str, str], ModuleType] = {}
MODULE_LOCK = threading.Lock()


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` unless it is there: temp file + atomic ``os.replace``."""
    if path.exists():
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".py")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        try:  # a hard link never replaces an existing file: the first writer wins
            os.link(tmp, path)
        except FileExistsError:
            pass
        except OSError:  # no hard links on this file system
            if not path.exists():
                os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


@functools.lru_cache(maxsize=256)
def module_name(source: str) -> str:
    """The name of the generated module with text ``source``: a hash of the text (kept
    for the last texts asked: a structure's text is one string object, whose own hash
    Python keeps)."""
    return f"lumped_jit_{hashlib.sha256(source.encode()).hexdigest()[:24]}"


def loaded_key(name: str) -> tuple[str, str]:
    """The key of module ``name`` in :data:`LOADED_MODULES`: with the cache directory it
    was imported from, so that a module compiled into another cache (a test's temporary
    one, a changed ``LUMPED_CACHE_DIR``) is not taken for this cache's."""
    return str(cache_dir()), name


def module_cached(source: str) -> bool:
    """The generated module with text ``source`` is loaded in this process, or its file
    is in the disk cache (compiled by an earlier run on this machine)."""
    return generated_module_exists(module_name(source))


def generated_module_exists(name: str) -> bool:
    """The generated module ``name`` is loaded in this process (under
    :func:`loaded_key` ``(name)``) or its file is in the disk cache (``cache_dir()/jit``)."""
    return (loaded_key(name) in LOADED_MODULES
            or (cache_dir() / "jit" / f"{name}.py").exists())


def import_generated(name: str, source: str) -> ModuleType:
    """Write ``source`` to the disk cache as module ``name`` (once) and import it; an
    unwritable cache falls back to a temporary directory, with a warning (nothing is
    kept). The caller holds ``MODULE_LOCK`` and records the module."""
    path = cache_dir() / "jit" / f"{name}.py"
    try:
        _write_once(path, source)
    except OSError as err:  # an unwritable cache: compile, but nothing is kept
        warnings.warn(f"lumped: cannot write the compiled-code cache {path.parent} "
                      f"({err}); using a temporary directory", stacklevel=3)
        path = Path(tempfile.mkdtemp(prefix="lumped-jit-")) / f"{name}.py"
        _write_once(path, source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
