"""A one-storey structure on a friction isolator under the shipped synthetic record.

Two masses in the frame of the shaken ground: the base slab ``base`` on a Coulomb slider
(``tau = mu (m_b + m_s) g``) with a restoring ``linear_spring`` (an isolation period of
2.5 s), and the storey ``top`` on a spring and a viscous damper (a fixed-base period of
0.4 s, 2 % damping). The fixed-base structure is the same storey on the ground. The
record is ``examples/records/synthetic_ground.at2`` (in g). Writes ``docs/isolator.png``
(or ``--out``): the storey's absolute acceleration and drift, isolated and fixed-base;
the isolator's loop (spring + slider); the base's displacement with the slider's stick
intervals shaded. See docs/records_and_loops.md.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import read_at2
from lumped.post import hysteresis
from lumped.scene import GroundMotion

HERE = Path(__file__).resolve().parent
M_BASE, M_TOP, G = 1000.0, 1000.0, 9.80665
K_TOP = M_TOP * (2 * math.pi / 0.4) ** 2                 # storey: T = 0.4 s
C_TOP = 2 * 0.02 * math.sqrt(K_TOP * M_TOP)              # 2 % damping
K_ISO = (M_BASE + M_TOP) * (2 * math.pi / 2.5) ** 2      # isolator: T = 2.5 s
TAU = 0.05 * (M_BASE + M_TOP) * G                        # friction coefficient 0.05


def storey(ground: GroundMotion, on: str) -> list[Element]:
    return [Element("storey", get_law("linear_spring").bind(k=K_TOP), on, "top"),
            Element("storey_damper", get_law("bingham").bind(gamma=1.0 / C_TOP, tau=0.0),
                    on, "top")]


def scenes(record) -> tuple[Scene, Scene]:
    ground = GroundMotion(acceleration=record)
    isolated = Scene(
        [Mass("base", m=M_BASE), Mass("top", m=M_TOP)],
        [Element("slider", get_law("coulomb").bind(tau=TAU, r=1e3), "ground", "base"),
         Element("iso_spring", get_law("linear_spring").bind(k=K_ISO), "ground", "base"),
         *storey(ground, "base")], ground_motion=ground)
    fixed = Scene([Mass("top", m=M_TOP)], storey(ground, "ground"), ground_motion=ground)
    return isolated, fixed


def main(out: Path, t_end: float = 20.0) -> dict[str, float]:
    record = read_at2(HERE / "records" / "synthetic_ground.at2")  # units from the header
    isolated, fixed = scenes(record)
    iso = simulate(isolated, method="bdf2", dt=2.5e-3, t_end=t_end)
    fix = simulate(fixed, method="bdf2", dt=2.5e-3, t_end=t_end)
    drift_iso = iso.x["top"] - iso.x["base"]
    sticks = iso.stick_intervals("slider")
    numbers = {
        "peak ground acceleration (g)": float(np.abs(iso.ground.a).max() / G),
        "peak storey acceleration, fixed base (g)": float(np.abs(fix.absolute.a["top"]).max()
                                                         / G),
        "peak storey acceleration, isolated (g)": float(np.abs(iso.absolute.a["top"]).max()
                                                       / G),
        "peak storey drift, fixed base (mm)": float(np.abs(fix.x["top"]).max() * 1e3),
        "peak storey drift, isolated (mm)": float(np.abs(drift_iso).max() * 1e3),
        "peak isolator displacement (mm)": float(np.abs(iso.x["base"]).max() * 1e3),
        "time stuck (s)": float(sum(b - a for a, b in sticks)),
    }
    for key, value in numbers.items():
        print(f"{key}: {value:.4g}")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(10.0, 7.0), layout="constrained")
    t = iso.t
    ax[0, 0].plot(t, fix.absolute.a["top"] / G, lw=0.7, label="fixed base")
    ax[0, 0].plot(t, iso.absolute.a["top"] / G, lw=0.7, label="isolated")
    ax[0, 0].set(xlabel="t (s)", ylabel="storey absolute acceleration (g)")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].plot(t, fix.x["top"] * 1e3, lw=0.7, label="fixed base")
    ax[0, 1].plot(t, drift_iso * 1e3, lw=0.7, label="isolated")
    ax[0, 1].set(xlabel="t (s)", ylabel="storey drift (mm)")
    ax[0, 1].legend(fontsize=8)
    loop = hysteresis(iso, ["iso_spring", "slider"])
    ax[1, 0].plot(loop.elongation * 1e3, loop.force / 1e3, lw=0.7)
    ax[1, 0].set(xlabel="isolator displacement q (mm)", ylabel="spring + slider force (kN)",
                 title="isolator loop")
    ax[1, 1].plot(t, iso.x["base"] * 1e3, lw=0.7, color="k")
    for a, b in sticks:
        ax[1, 1].axvspan(a, b, color="tab:orange", alpha=0.3, lw=0)
    ax[1, 1].set(xlabel="t (s)", ylabel="base displacement relative to ground (mm)",
                 title="slider stuck (shaded)")
    fig.suptitle("One storey on a friction isolator, synthetic record (peak 0.3 g)")
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"wrote {out}")
    return numbers


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE.parent / "docs" / "isolator.png")
    main(parser.parse_args().out)
