#!/usr/bin/python3
"""Benchmark (prints figures): fits the on-chip tile-buffer bandwidth to the FLAT part of
Imagination's GX6250 measurements, then predicts the step past the on-chip budget without further
tuning.

Published (Imagination, PowerVR Performance Recommendations, "On-Chip Memory Performance": the
PowerVR SDK Deferred Shading example keeping a growing G-buffer on chip, depth separate, on a GX6250
with 256 bits per pixel on chip), ms per frame:
    96 bit 20, 128 21, 160 23, 192 24, 224 28, 256 29, 288 39.
The flat part (96 .. 256 bits, inside the budget) has a slope: finite on-chip bandwidth. The step
(256 -> 288 bits, +34 %) is the budget.

Here: deferred gbuffer_storage=onchip on the atrium (the colour target plus 2 .. 8 G-buffer targets,
the setup of `tbdrsim validate`'s cliff row), configs/series6xt_gx6250.ini. The only unknown is
pls.tile_buffer_bytes_per_clock (per USC; no public figure). The fit: for each candidate value the
six flat-part frame times T_i, scaled by the one factor s that best matches the published P_i in
least squares (s = sum T_i P_i / sum T_i^2: the scene and resolution differ from the SDK example's,
so only the shape is comparable), and the RMS of s T_i - P_i in ms; a golden-section search on
log(value) refines the best candidate. Then the 288-bit point at the fitted value: predicted step
T_288 / T_256 - 1 against the published 39 / 29 - 1 = +34.5 %.

Usage: /usr/bin/python3 bench/onchip_cliff_fit.py [--build build] [--resolution 480x270]
       [--scene atrium:2] [--lights 64]
"""
import argparse
import math
import os
import sqlite3
import subprocess
import sys
import tempfile

PUBLISHED_BITS = [96, 128, 160, 192, 224, 256, 288]
PUBLISHED_MS = [20.0, 21.0, 23.0, 24.0, 28.0, 29.0, 39.0]
#: Candidate tile-buffer bandwidths per USC (bytes/clock) the coarse scan tries.
CANDIDATES = [2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 64.0, 128.0]
#: Golden-section refinement steps on log(value) around the best candidate (each one frame set).
REFINE_STEPS = 8


def layout(bits):
    """The G-buffer layout of `bits` per pixel of colour-like storage, the colour target included."""
    k = bits // 32 - 1
    if k <= 7:
        return ",".join(["rgba8"] * k)
    return "rgba8,rgba8,rgba8,rgba8,rgba8,rgba8,rgba16f"  # 8 outputs at most: the last one 64-bit


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--resolution", default="480x270")
    ap.add_argument("--scene", default="atrium:2")
    ap.add_argument("--lights", default="64")
    args = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    tool = os.path.abspath(os.path.join(args.build, "tbdrsim"))
    config = os.path.join(root, "configs", "series6xt_gx6250.ini")
    with tempfile.TemporaryDirectory() as tmp:
        traces = {}
        for bits in PUBLISHED_BITS:
            traces[bits] = os.path.join(tmp, "cliff_%d.trace" % bits)
            subprocess.run([tool, "trace", "--technique", "deferred", "--scene", args.scene, "--lights", args.lights,
                            "--resolution", args.resolution, "--option", "gbuffer=" + layout(bits), "--option",
                            "gbuffer_storage=onchip", "--out", traces[bits]], check=True, stdout=subprocess.DEVNULL)
        runs = [0]

        def frame_ms(bits, bpc):
            runs[0] += 1
            db = os.path.join(tmp, "r%d.db" % runs[0])
            subprocess.run([tool, "run", "--trace", traces[bits], "--config", config, "--set",
                            "pls.tile_buffer_bytes_per_clock=%.6g" % bpc, "--db", db, "--quiet"], check=True)
            with sqlite3.connect(db) as c:
                return c.execute("SELECT value FROM stats WHERE scope = 'frame/timing' AND name = 'frame_time_ms'"
                                 ).fetchone()[0]

        cache = {}

        def fit(bpc):
            """(rms ms, scale, flat-part times) of one candidate."""
            if bpc not in cache:
                t = [frame_ms(b, bpc) for b in PUBLISHED_BITS[:-1]]
                p = PUBLISHED_MS[:-1]
                s = sum(a * b for a, b in zip(t, p)) / sum(a * a for a in t)
                rms = math.sqrt(sum((s * a - b) ** 2 for a, b in zip(t, p)) / len(t))
                cache[bpc] = (rms, s, t)
            return cache[bpc]

        print("deferred gbuffer_storage=onchip, %s, %s, %s lights, configs/series6xt_gx6250.ini" %
              (args.scene, args.resolution, args.lights))
        print("%-12s %10s %10s   %s" % ("bytes/clock", "rms ms", "scale", "flat-part ms (96 .. 256 bits)"))
        for bpc in CANDIDATES:
            rms, s, t = fit(bpc)
            print("%-12.4g %10.3f %10.3f   %s" % (bpc, rms, s, " ".join("%.3f" % x for x in t)))
        best = min(CANDIDATES, key=lambda b: fit(b)[0])
        i = CANDIDATES.index(best)
        lo = math.log(CANDIDATES[max(i - 1, 0)])
        hi = math.log(CANDIDATES[min(i + 1, len(CANDIDATES) - 1)])
        g = (math.sqrt(5) - 1) / 2
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        for _ in range(REFINE_STEPS):
            if fit(math.exp(a))[0] < fit(math.exp(b))[0]:
                hi, b = b, a
                a = hi - g * (hi - lo)
            else:
                lo, a = a, b
                b = lo + g * (hi - lo)
        best = min(cache, key=lambda k: cache[k][0])
        rms, s, t = fit(best)
        t288 = frame_ms(288, best)
        slope_model = t[-1] / t[0] - 1
        slope_pub = PUBLISHED_MS[5] / PUBLISHED_MS[0] - 1
        step_model = t288 / t[-1] - 1
        step_pub = PUBLISHED_MS[6] / PUBLISHED_MS[5] - 1
        print()
        print("fitted pls.tile_buffer_bytes_per_clock = %.3g (rms %.3f ms after scaling by %.3f; %d runs)" %
              (best, rms, s, runs[0]))
        print("%-6s %12s %12s %10s" % ("bits", "model ms", "scaled ms", "GX6250 ms"))
        for bits, ms in zip(PUBLISHED_BITS, t + [t288]):
            print("%-6d %12.4f %12.2f %10.0f" % (bits, ms, s * ms, PUBLISHED_MS[PUBLISHED_BITS.index(bits)]))
        print("flat part 96 -> 256 bits: model %+.1f %%, GX6250 %+.1f %% (fitted)" % (100 * slope_model, 100 * slope_pub))
        print("step 256 -> 288 bits:     model %+.1f %%, GX6250 %+.1f %% (predicted, not fitted): error %+.1f points" %
              (100 * step_model, 100 * step_pub, 100 * (step_model - step_pub)))


if __name__ == "__main__":
    sys.exit(main())
