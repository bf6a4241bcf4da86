"""Progress on a terminal, silence elsewhere (issue 7, point 4)."""

from __future__ import annotations

import io
import sys

import pytest

from lumped.cli import main
from lumped.cli import progress as progress_mod
from lumped.cli.progress import Progress, progress_wanted


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_wanted_only_on_a_terminal_and_not_quiet():
    assert progress_wanted(False, _Tty())
    assert not progress_wanted(True, _Tty())
    assert not progress_wanted(False, io.StringIO())
    assert not progress_wanted(False, object())  # no isatty at all


def test_a_disabled_bar_writes_nothing():
    out = io.StringIO()
    with Progress(5, "x", enabled=False, stream=out, delay=0.0) as bar:
        for _ in range(5):
            bar.update(note="run")
    assert out.getvalue() == ""


def test_the_tqdm_bar_counts_and_is_removed():
    pytest.importorskip("tqdm")  # in the `test` extra: CI runs this
    out = io.StringIO()
    with Progress(4, "runs", stream=out, delay=0.0) as bar:
        for i in range(4):
            bar.update(note=f"run {i}")
    text = out.getvalue()
    assert "runs:" in text and "/4" in text


def test_the_plain_counter_without_tqdm(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)  # import fails: the fallback
    out = io.StringIO()
    with Progress(3, "runs", stream=out, delay=0.0) as bar:
        for i in range(3):
            bar.update(note=f"scene {i}")
    text = out.getvalue()
    assert "[3/3]" in text and "scene 2" in text and text.endswith("\n")


def test_the_delay_keeps_short_work_silent(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    out = io.StringIO()
    with Progress(3, "runs", stream=out, delay=60.0) as bar:
        bar.update(3)
    assert out.getvalue() == ""


@pytest.mark.parametrize("quiet", [False, True])
def test_paper_prints_no_progress_to_a_non_terminal(tmp_path, capsys, monkeypatch, quiet):
    monkeypatch.setattr(progress_mod, "PROGRESS_DELAY", 0.0)
    argv = ["paper", "--out", str(tmp_path), "--scenario", "release-0.005", "--dt", "1e-3"]
    assert main(argv + (["--quiet"] if quiet else [])) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert (out == "") if quiet else ("release-0.005" in out)
    assert (tmp_path / "release-0.005.csv").exists()


def test_paper_shows_progress_on_a_terminal(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(progress_mod, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    argv = ["paper", "--out", str(tmp_path), "--scenario", "release-0.005", "--dt", "1e-3"]
    assert main(argv) == 0
    assert "lumped paper" in capsys.readouterr().err
    assert main(argv + ["--quiet"]) == 0
    assert capsys.readouterr() == ("", "")


@pytest.mark.parametrize("quiet", [False, True])
def test_bench_prints_no_progress_to_a_non_terminal(tmp_path, capsys, monkeypatch, quiet):
    monkeypatch.setattr(progress_mod, "PROGRESS_DELAY", 0.0)
    methods = "scipy-events-DOP853" if quiet else "closed-bdf2,scipy-events-DOP853"
    argv = ["bench", "--out", str(tmp_path), "--quick", "--scenes", "release-0.5",
            "--methods", methods, "--no-creep", "--no-events"]
    assert main(argv + (["--quiet"] if quiet else [])) == 0
    out, err = capsys.readouterr()
    assert err == ""
    if quiet:
        assert out == ""
    else:
        assert "runs" in out and "| release-0.5 |" in out
        assert "closed-bdf2 / scipy-events-DOP853" in out
    assert (tmp_path / "summary.md").exists()


def test_bench_refuses_an_unknown_method(tmp_path, capsys):
    argv = ["bench", "--out", str(tmp_path), "--quick", "--methods", "closed-bdf2,nope"]
    assert main(argv) == 2
    assert "`--methods`" in capsys.readouterr().err
