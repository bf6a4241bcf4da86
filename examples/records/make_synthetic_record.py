"""Write the synthetic ground-acceleration record shipped with lumped.

The record is made up (no measured record's licence is involved), by a documented
recipe, so anyone can regenerate it:

1. white Gaussian noise ``w_k`` at ``dt = 0.005 s`` on ``[0, 20] s`` (4001 samples),
   ``numpy.random.default_rng(28).standard_normal``;
2. the Kanai-Tajimi filter (ground of frequency ``f_g = 2.5 Hz``, damping ``zeta_g = 0.6``)
   ``H_g(s) = (2 zeta_g w_g s + w_g^2) / (s^2 + 2 zeta_g w_g s + w_g^2)``, then the
   Clough-Penzien high-pass ``H_f(s) = s^2 / (s^2 + 2 zeta_f w_f s + w_f^2)``
   (``f_f = 0.25 Hz``, ``zeta_f = 0.6``), each discretised by the bilinear transform
   (``scipy.signal.bilinear``) and applied with ``scipy.signal.lfilter``;
3. times a Jennings envelope: ``(t / 2)^2`` up to 2 s, ``1`` up to 8 s, then
   ``exp(-0.35 (t - 8))``, and a cosine taper over the last second (so the record
   starts and ends at exactly 0);
4. scaled to a peak of ``0.3 g`` and rounded to 7 significant digits.

No baseline correction is applied: integrating it gives a velocity and a displacement
that drift a little, as measured records do (see ``docs/records_and_loops.md``).

It writes ``synthetic_ground.at2`` (PEER NGA format, units of g) and its twin
``synthetic_ground.csv`` (columns ``t`` in s and ``acceleration_g`` in g, the same
numbers). Run: ``python examples/records/make_synthetic_record.py [--out DIR]``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy import signal

DT, DURATION, PEAK_G, SEED = 0.005, 20.0, 0.3, 28


def _filtered(s_num: list[float], s_den: list[float], x: np.ndarray) -> np.ndarray:
    b, a = signal.bilinear(s_num, s_den, fs=1.0 / DT)
    return signal.lfilter(b, a, x)


def envelope(t: np.ndarray) -> np.ndarray:
    """The Jennings envelope with a cosine taper over the last second."""
    env = np.where(t < 2.0, (t / 2.0) ** 2, np.where(t <= 8.0, 1.0, np.exp(-0.35 * (t - 8.0))))
    tail = t > DURATION - 1.0
    env[tail] *= 0.5 * (1.0 + np.cos(math.pi * (t[tail] - (DURATION - 1.0))))
    return env


def synthetic_record() -> tuple[np.ndarray, np.ndarray]:
    """``(t, a)``: times (s) and ground acceleration (g), 7 significant digits."""
    n = round(DURATION / DT) + 1
    t = np.arange(n) * DT
    noise = np.random.default_rng(SEED).standard_normal(n)
    wg, zg = 2.0 * math.pi * 2.5, 0.6
    wf, zf = 2.0 * math.pi * 0.25, 0.6
    a = _filtered([2 * zg * wg, wg**2], [1.0, 2 * zg * wg, wg**2], noise)
    a = _filtered([1.0, 0.0, 0.0], [1.0, 2 * zf * wf, wf**2], a)
    a *= envelope(t)
    a *= PEAK_G / np.abs(a).max()
    return t, np.array([float(f"{y:.6e}") + 0.0 for y in a])


def write(out: Path) -> tuple[Path, Path]:
    t, a = synthetic_record()
    out.mkdir(parents=True, exist_ok=True)
    at2 = out / "synthetic_ground.at2"
    rows = ["".join(f"{y:15.6E}" for y in a[k:k + 5]) for k in range(0, len(a), 5)]
    at2.write_text("PEER NGA STRONG MOTION DATABASE RECORD (FORMAT ONLY)\n"
                   "SYNTHETIC GROUND MOTION, LUMPED EXAMPLES, RECIPE IN "
                   "MAKE_SYNTHETIC_RECORD.PY\n"
                   "ACCELERATION TIME SERIES IN UNITS OF G\n"
                   f"NPTS= {len(a):5d}, DT= {DT:.4f} SEC\n" + "\n".join(rows) + "\n")
    csv = out / "synthetic_ground.csv"
    csv.write_text("t,acceleration_g\n"
                   + "".join(f"{tk:.3f},{y:.7g}\n" for tk, y in zip(t, a, strict=True)))
    return at2, csv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = parser.parse_args()
    at2, csv = write(args.out)
    t, a = synthetic_record()
    print(f"wrote {at2.name} and {csv.name} to {args.out}: {len(t)} points, dt {DT} s, "
          f"{DURATION:g} s, peak {np.abs(a).max():g} g")


if __name__ == "__main__":
    main()
