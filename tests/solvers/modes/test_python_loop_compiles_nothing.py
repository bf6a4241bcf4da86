"""A default ``radau5`` first run of a structure in the Python loop compiles nothing with
numba (issue 27: a first run on a fresh machine). Counted, not timed: a fresh process
with empty caches records numba's compile events during the run."""

from __future__ import annotations

import json
import os
import subprocess
import sys

_CHILD = r"""
import json
from numba.core import event
from lumped import simulate
from lumped.scenarios import scenario_scene

compiled = []


class Recorder(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev):
        pass


scene = scenario_scene("forcing-F2")
event.register("numba:compile", Recorder())
sol = simulate(scene, method="radau5", t_end=2.0)
print(json.dumps({"ok": bool(sol.ok), "loop": str(sol.stats["loop"]), "compiled": compiled}))
"""


def test_a_default_radau5_first_run_in_the_python_loop_compiles_nothing(tmp_path):
    # the burst makes the dashpot stick and slip: the events' crossing root runs
    env = dict(os.environ)
    for var in ("NUMBA_CACHE_DIR", "LUMPED_CACHE_DIR", "XDG_CACHE_HOME"):
        env[var] = str(tmp_path / var.lower())
    out = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True,
                         text=True, check=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["ok"]
    assert got["loop"].startswith("python")
    assert got["compiled"] == []
