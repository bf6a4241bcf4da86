"""``benchmarks/property_counts.py``: the counts it reads off hypothesis's statistics."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "property_counts.py"
_spec = importlib.util.spec_from_file_location("property_counts", _PATH)
property_counts = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(property_counts)

_STATISTICS = """
tests/solvers/test_random_networks.py::test_random_passive_network[bdf1]:

  - during generate phase (2043.11 seconds):
    - Typical runtimes: ~ 6-656 ms, of which ~ 2-312 ms in data generation
    - 10000 passing, 0 failing, and 1358 invalid test cases
  - Stopped because settings.max_examples=10000
"""


def test_counts_reads_hypothesis_statistics():
    assert property_counts.counts(_STATISTICS) == (10000, 0, 1358)


def test_counts_sums_the_statistics_of_every_test_run():
    two = _STATISTICS + _STATISTICS.replace("10000 passing, 0 failing, and 1358",
                                            "17 passing, 1 failing, and 2")
    assert property_counts.counts(two) == (10017, 1, 1360)


def test_no_statistics_is_no_count():
    assert property_counts.counts("ERROR: file or directory not found") is None


@pytest.mark.parametrize("argv", [["--examples", "0"], ["--chunk", "1"],
                                  ["--methods", "radau6"]])
def test_bad_arguments_are_refused(argv, capsys):
    with pytest.raises(SystemExit) as err:
        property_counts.main(argv)
    assert err.value.code == 2
    assert argv[-1] in capsys.readouterr().err
