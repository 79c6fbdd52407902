#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the measured data of the examples that read tables (docs/model-format.md, "Tables").

The data are synthesised, not measured, and the examples say so:
  tracking_recorded_trajectory.yaml  a joint angle "recorded" at 20 Hz: two sines and a slow
                                      drift, rounded to 1e-4 rad (an encoder's resolution)
  shaken_frame.yaml                   a ground acceleration "recorded" at 50 Hz for 10 s: 60
                                      sines with Kanai–Tajimi amplitudes (ω_g = 15 rad/s,
                                      ζ_g = 0.6) and random phases (seed 7) under a
                                      build-up/strong/decay envelope, scaled to a peak of 3 m/s²,
                                      rounded to 1 mm/s²
Run it from the repository's root; it rewrites the `data:` blocks between the markers
"# --- data (scripts/make_example_tables.py) ---" and the next blank line of each file.
Uses the standard library only (no NumPy), so that its output is the same everywhere.
"""
import math
import random
import re
from pathlib import Path

MARK = "# --- data (scripts/make_example_tables.py) ---"


def flow(name, values, fmt, indent=6, width=96):
    """`name: [v, v, …]` wrapped at `width` columns."""
    lines, line = [], " " * indent + name + ": ["
    cont = " " * (indent + len(name) + 3)
    for k, v in enumerate(values):
        text = fmt(v) + ("]" if k == len(values) - 1 else ",")
        if len(line) + 1 + len(text) > width:
            lines.append(line.rstrip())
            line = cont
        line += ("" if line.endswith("[") or line == cont else " ") + text
    lines.append(line)
    return "\n".join(lines)


def number(v, digits):
    s = f"{v:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def tracking():
    t = [k * 0.05 for k in range(81)]  # 0 … 4 s at 20 Hz
    th = [0.6 * math.sin(1.3 * x) + 0.25 * math.sin(3.1 * x + 0.4) + 0.05 * x - 0.25 * math.sin(0.4)
          for x in t]
    return "\n".join([flow("t", t, lambda v: number(v, 2)),
                      flow("theta", th, lambda v: number(v, 4))])


def ground():
    rng = random.Random(7)
    wg, zg = 15.0, 0.6
    waves = []
    for k in range(60):
        w = 2 * math.pi * (0.3 + k * 0.25)  # 0.3 … 15 Hz
        r = (w / wg) ** 2
        kt = (1 + 4 * zg * zg * r) / ((1 - r) ** 2 + 4 * zg * zg * r)
        waves.append((w, math.sqrt(kt), rng.uniform(0, 2 * math.pi)))

    def envelope(x):
        return (x / 1.5) ** 2 if x < 1.5 else 1.0 if x < 4.5 else math.exp(-0.6 * (x - 4.5))

    t = [k * 0.02 for k in range(501)]  # 0 … 10 s at 50 Hz
    a = [envelope(x) * sum(c * math.sin(w * x + p) for w, c, p in waves) for x in t]
    peak = max(abs(v) for v in a)
    a = [3.0 * v / peak for v in a]
    return "\n".join([flow("t", t, lambda v: number(v, 2)),
                      flow("acc", a, lambda v: number(v, 3))])


def rewrite(path, block):
    text = path.read_text()
    start = text.index(MARK) + len(MARK) + 1
    end = text.index("\n\n", start - 1)
    path.write_text(text[:start] + block + text[end:])


if __name__ == "__main__":
    models = Path("examples/models")
    rewrite(models / "tracking_recorded_trajectory.yaml", tracking())
    rewrite(models / "shaken_frame.yaml", ground())
