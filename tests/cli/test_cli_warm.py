"""``lumped warm SCENE.toml``: compile a scene file's structure ahead of time."""

from __future__ import annotations

from pathlib import Path

import pytest

from lumped.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_warm_fills_an_empty_cache_and_says_what_it_compiled(tmp_path, monkeypatch, capsys):
    cache = tmp_path / "cache"
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(cache))
    assert main(["warm", str(EXAMPLES / "release-0.5.toml")]) == 0
    out = capsys.readouterr().out
    assert f"loaded from the cache {cache}" in out
    assert "radau5" in out and "Radau IIA loop" in out
    assert "jit-bdf2" in out and "the fast loop and the faithful port" in out
    assert "jit-bdf1" not in out
    assert out.count("s CPU") == 3  # two methods and the total
    assert any((cache / "jit").glob("*.py"))  # the generated modules are on disk


def test_warm_compiles_the_loop_of_a_scene_at_rest(tmp_path, monkeypatch, capsys):
    # release-0.005 never moves: radau5 holds it without a loop, warm compiles the loop
    # for the runs of its structure that move
    cache = tmp_path / "cache"
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(cache))
    assert main(["warm", str(EXAMPLES / "release-0.005.toml"), "--method", "radau5"]) == 0
    assert "the event-driven Radau IIA loop" in capsys.readouterr().out
    assert any((cache / "jit").glob("*.py"))


def test_warm_compiles_the_kernels_a_first_run_would_compile(tmp_path, monkeypatch, capsys):
    """The kernels the compiled loop calls through addresses (the stage solve, the error
    estimate, the crossing test) and the probe's branch selector are compiled at their
    first use; warm's short run of a scene at rest uses none of them, and a user's first
    run after ``lumped warm forcing-F2.toml`` compiled them (5.3 s of CPU). Here every
    store starts empty, as in a process that never compiled them."""
    from lumped.solvers.eventdriven import fast_parts
    from lumped.solvers.radau import stage_jit, step_jit

    stores = [(stage_jit, "_STAGE"), (step_jit, "_ERROR"), (step_jit, "_CROSSED"),
              (fast_parts, "_BRANCH")]
    for module, name in stores:
        monkeypatch.setattr(module, name, [])
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path / "cache"))
    assert main(["warm", str(EXAMPLES / "release-0.005.toml"), "--method", "radau5"]) == 0
    capsys.readouterr()
    assert all(getattr(module, name) for module, name in stores)


def test_method_is_repeatable_and_a_locked_scene_is_compiled_too(capsys):
    # a taut string (position lock) runs compiled in jit-bdf1 since issue 27 (the
    # reference takes only the steps across a new lock): warm compiles its loops
    assert main(["warm", str(EXAMPLES / "lock.toml"), "--method", "jit-bdf1",
                 "--method", "jit-bdf1"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if "jit-bdf1" in line]
    assert len(lines) == 1 and "the faithful port" in lines[0]
    assert "runs on the Python solver" not in out
    assert "radau5" not in out and "jit-bdf2" not in out


@pytest.mark.parametrize("make,message", [
    (lambda d: d / "missing.toml", "missing.toml: no such scene file"),
    (lambda d: d, "cannot read the scene file"),
    (lambda d: (d / "bad.toml", (d / "bad.toml").write_text("x = \n"))[0], "bad.toml: not valid"),
])
def test_bad_input_exits_2_naming_the_file(tmp_path, capsys, make, message):
    path = make(tmp_path)
    assert main(["warm", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("lumped warm: error: ") and message in err and str(path) in err


def test_an_unknown_method_is_a_usage_error(capsys):
    assert main(["warm", str(EXAMPLES / "release-0.5.toml"), "--method", "bdf2"]) == 2
    assert "invalid choice: 'bdf2'" in capsys.readouterr().err
    assert main(["warm", "--help"]) == 0
    assert "usage: lumped warm" in capsys.readouterr().out
