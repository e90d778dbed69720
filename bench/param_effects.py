#!/usr/bin/env python3
"""Parameter-effect bench: what each hardware parameter moves (bench/param_effects.sh runs it).

Reads the parameter list from `tbdrsim params --format markdown` (so a parameter added later is
covered without touching this file), makes a few small reference traces (`tbdrsim trace`), and
for every parameter replays each trace with the real CLI (`tbdrsim run --set key=value`) at a low
and a high value (numbers: half and twice the default, clamped to the declared range; a zero
default: the range's bottom and ZERO_DEFAULT_HIGH; booleans: false and true; choices: every
choice). For each parameter it prints the relative change from the low to the high value of the
frame time (frame/timing frame_time_ms), the DRAM bytes at the device (mem/dram read_bytes +
write_bytes) and the frame energy (frame/energy total_pj), each the largest over the workloads,
and the other statistic that moved most. A value the configuration refuses is reported as such.
The simulator is deterministic: "none" means the three figures were bit-identical on every
workload.
"""
import argparse
import concurrent.futures
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import time

# The figures the table reports first: (label, scope, names summed).
HEADLINE = [
    ("frame_time", "frame/timing", ("frame_time_ms",)),
    ("dram_bytes", "mem/dram", ("read_bytes", "write_bytes")),
    ("energy", "frame/energy", ("total_pj",)),
]
# A zero default has no "twice": the high value is this fraction of the range above its bottom,
# capped at ZERO_DEFAULT_HIGH_CAP (so a [0, 1e9] ns range tries 100 ns, not 10 ms).
ZERO_DEFAULT_FRACTION = 0.01
ZERO_DEFAULT_HIGH_CAP = 100.0
# Statistics that restate the configuration rather than measure the run.
CONFIG_ECHO = {("mem/dram", "peak_bandwidth_gbps")}
# Per-unit figures that are the frame time's other side (a unit not busy is idle or stalled).
IDLE_FIGURES = {"idle_cycles", "stalled_cycles", "utilization"}


def parse_params(build):
    """Every declared parameter: (key, type, default, range text) from the markdown reference."""
    text = subprocess.run([os.path.join(build, "tbdrsim"), "params", "--format", "markdown"], check=True,
                          capture_output=True, text=True).stdout
    params = []
    for line in text.splitlines():
        if not line.startswith("| `"):
            continue
        cells = [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        key, default, unit, rng = cells[0].strip("`"), cells[1], cells[2], cells[3]
        params.append((key, default, unit, rng))
    return params


def number(text):
    return float(text) if text not in ("inf", "-inf") else float(text)


def values_for(default, rng):
    """The values to try, or None for a free-text parameter (a label)."""
    if rng == "any text":
        return None
    if rng == "true|false":
        return ["false", "true"]
    if rng.startswith("one of "):
        return rng[len("one of "):].split("|")
    m = re.fullmatch(r"\[(\S+), (\S+)\]", rng)
    if not m:
        raise SystemExit("param_effects: cannot read the range '%s'" % rng)
    lo, hi = number(m.group(1)), number(m.group(2))
    is_int = re.fullmatch(r"-?\d+", default) is not None and re.fullmatch(r"-?\d+", m.group(1)) is not None
    d = float(default)
    if d > 0:
        low, high = max(lo, d / 2), min(hi, d * 2)
    else:
        span = hi - lo if hi != float("inf") else ZERO_DEFAULT_HIGH_CAP
        low, high = lo, min(hi, lo + max(min(span * ZERO_DEFAULT_FRACTION, ZERO_DEFAULT_HIGH_CAP), 1.0))
    if is_int:
        low, high = int(round(low)), int(round(high))
        if low == high:
            return None
        return [str(low), str(high)]
    fmt = lambda v: ("%.6g" % v)
    return [fmt(low), fmt(high)] if fmt(low) != fmt(high) else None


def run_one(build, trace, sets, db):
    cmd = [os.path.join(build, "tbdrsim"), "run", "--trace", trace, "--db", db, "--quiet", "--threads", "1"]
    for s in sets:
        cmd += ["--set", s]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:  # the binary being rebuilt meanwhile, say: report it, keep the others
        return {"error": "cannot run %s: %s" % (cmd[0], e)}
    if p.returncode != 0:
        msg = (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
        msg = re.sub(r"^error: \S*\.trace(:\d+)?: ", "", msg)  # the scratch trace path says nothing
        return {"error": msg}
    con = sqlite3.connect(db)
    rows = con.execute("SELECT scope, name, value FROM stats WHERE run_id = (SELECT max(id) FROM runs)").fetchall()
    con.close()
    os.remove(db)
    return {(s, n): v for s, n, v in rows}


def figure(stats, scope, names):
    return sum(stats.get((scope, n), 0.0) for n in names)


def rel(a, b):
    """Relative change from a to b (b - a) / |a|; inf when a is 0 and b is not."""
    if a == b:
        return 0.0
    if a == 0:
        return float("inf") if b > 0 else float("-inf")
    return (b - a) / abs(a)


def pct(x):
    if x in (float("inf"), float("-inf")):
        return "0 -> >0" if x > 0 else ">0 -> 0"
    return "%+.2f %%" % (100 * x)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", "-j", type=int, default=2)
    ap.add_argument("--scene", default="atrium:1")
    ap.add_argument("--resolution", default="320x180")
    ap.add_argument("--lights", default="64")
    ap.add_argument("--techniques", default="deferred,forward_plus,plain_forward,deferred_tile_store,tiled_deferred,"
                                            "visibility_buffer")
    ap.add_argument("--only", default="", help="regular expression: the parameters to measure (default all)")
    ap.add_argument("--base", action="append", default=[], metavar="KEY=VALUE",
                    help="a --set applied to every run before the measured one (e.g. gpu.mode=imr), repeatable")
    args = ap.parse_args()
    if args.jobs < 1:
        sys.exit("param_effects: --jobs expects a positive integer")
    tmp = tempfile.mkdtemp(prefix="param_effects.")
    try:
        measure(args, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def measure(args, tmp):
    start = time.time()
    tbdrsim = os.path.join(args.build, "tbdrsim")
    traces = {}
    for t in args.techniques.split(","):
        path = os.path.join(tmp, t + ".trace")
        subprocess.run([tbdrsim, "trace", "--technique", t, "--scene", args.scene, "--lights", args.lights,
                        "--resolution", args.resolution, "--out", path], check=True, capture_output=True)
        traces[t] = path
    params = [p for p in parse_params(args.build) if re.search(args.only, p[0])]
    jobs = []  # (key, value, technique)
    plan = {}
    for key, default, unit, rng in params:
        vals = values_for(default, rng)
        plan[key] = (default, unit, vals)
        for v in vals or []:
            for t in traces:
                jobs.append((key, v, t))
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futs = {pool.submit(run_one, args.build, traces[t], args.base + ["%s=%s" % (k, v)],
                            os.path.join(tmp, "%d.db" % i)): (k, v, t) for i, (k, v, t) in enumerate(jobs)}
        for f in concurrent.futures.as_completed(futs):
            results[futs[f]] = f.result()

    print("| parameter | default | values (first / last) | frame_time | dram_bytes | energy | other frame statistic moved most | effect |")
    print("|---|---|---|---|---|---|---|---|")
    inert = []
    for key, default, unit, rng in params:
        _, _, vals = plan[key]
        if not vals:
            print("| `%s` | %s | - | | | | | not run: %s |" % (key, default, "a label (free text)" if rng == "any text"
                                                                 else "no distinct low/high value in " + rng))
            inert.append(key)
            continue
        errors = sorted({r["error"] for (k, v, t), r in results.items() if k == key and "error" in r})
        cols, moved = [], False
        for label, scope, names in HEADLINE:
            best, where = 0.0, ""
            for t in traces:
                figs = [figure(results[(key, v, t)], scope, names) for v in vals if "error" not in results[(key, v, t)]]
                if len(figs) < 2:
                    continue
                # Two values: low -> high. Choices: the smallest -> the largest (spread).
                ch = rel(figs[0], figs[-1]) if len(vals) == 2 else rel(min(figs), max(figs))
                if abs(ch) > abs(best):
                    best, where = ch, t
            moved |= best != 0
            cols.append("%s (%s)" % (pct(best), where) if best else "0")
        other, other_ch = "", 0.0
        for t in traces:
            rs = [results[(key, v, t)] for v in vals if "error" not in results[(key, v, t)]]
            if len(rs) < 2:
                continue
            for name in rs[0]:
                # Frame-level statistics, less the host's (wall and CPU time), the headline figures, the configuration echoes and
                # the idle / stalled / utilisation figures that restate the frame time.
                if (not name[0].startswith("frame/") or name[0] == "frame/host" or name in CONFIG_ECHO or name[1] in IDLE_FIGURES
                        or any(name[0] == s and name[1] in n for _, s, n in HEADLINE)):
                    continue
                xs = [r.get(name, 0.0) for r in rs]
                a, b = max(abs(x) for x in xs), min(abs(x) for x in xs)
                ch = (a - b) / a if a else 0.0  # symmetric: 0..1, finite when one side is 0
                if ch > other_ch:
                    other_ch, other = ch, "%s %s (%s)" % (name[0], name[1], t)
        other_col = "%s: %.1f %% of the larger" % (other, 100 * other_ch) if other else "none"
        if len(vals) == 2:
            direction = "at %s: " % vals[1] + ", ".join(
                "%s %s" % (lab, "up" if c.startswith(("+", "0 ->")) else "down")
                for (lab, _, _), c in zip(HEADLINE, cols) if c != "0")
        else:
            direction = "the choices differ (smallest to largest)"
        effect = direction if moved else "NONE on frame time, DRAM bytes, energy"
        if errors:
            effect += "; refused: " + "; ".join(errors)[:160]
        if not moved:
            inert.append(key)
        print("| `%s` | %s | %s | %s | %s | %s | %s | %s |" % (key, default, " / ".join(vals), cols[0], cols[1], cols[2],
                                                             other_col, effect))
    runs = len(jobs)
    print()
    print("%d parameters, %d runs on %d workloads (%s %s, %s lights: %s)%s, %.0f s with %d jobs" % (
        len(params), runs, len(traces), args.scene, args.resolution, args.lights, ", ".join(traces),
        "".join(" --set " + b for b in args.base), time.time() - start, args.jobs))
    print("no effect on frame time, DRAM bytes or energy: " + (", ".join(inert) if inert else "none"))


if __name__ == "__main__":
    main()
