#!/usr/bin/python3
"""Time by pass and unit: for each technique (and variant) of one configuration and light count,
the frame's timeline (left: each render pass's binning and tile work, each compute dispatch, from
its first to its last cycle, in ms) and how busy each timed unit was (right: busy and stalled
cycles as a share of the frame's cycles).

Reads a tbdrsim results database (v_run_summary, the per-command '<pass>/timing' statistics and
v_metric's unit.<unit> figures) of finished runs. The selection must hold one configuration, scene,
frame size and light count (pick them with --config, --lights, --where); of repetitions, the first
run is drawn (a run's timeline is not an average).

    tbdrsim plot passes --db study/study.db --lights 1024 --out passes.png
    /usr/bin/python3 analysis/plot_passes.py --db out/sweep.db --config series6xt_gx6450 --lights 256
"""
import re

import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt
pd = pc.pd

#: A pass's name is written in its bar when the bar is at least this share of the longest frame.
LABEL_MIN_SHARE = 0.06
#: A pass's name is shrunk down to this size (points) to fit its bar, else left out.
NAME_MIN_POINTS = 5
#: Inches per technique row (two timeline lanes, one bar per unit beside them).
ROW_HEIGHT = 0.62


def fit_names(fig, ax, names):
    """Keeps a pass's name only where it fits inside its bar (at the smallest readable size) and
    clear of the names kept already (later bars, drawn over earlier ones, first), so that names
    never run over each other or past their bar."""
    renderer = fig.canvas.get_renderer()
    kept = []
    for text, a, b in reversed(names):
        x0 = ax.transData.transform((a, 0))[0]
        x1 = ax.transData.transform((b, 0))[0]
        for size in (6, NAME_MIN_POINTS):
            text.set_fontsize(size)
            box = text.get_window_extent(renderer)
            if box.width + 4 <= x1 - x0 and not any(box.overlaps(k) for k in kept):
                kept.append(box)
                break
        else:
            text.remove()


def main():
    args, db, runs = pc.open_selection(__doc__, "passes.png", pc.flag(
        "--ms", "timeline in ms on one axis (default: each frame as 100 %%, its time written beside it)"))
    _, fixed = pc.facets(runs)  # one configuration, scene, frame and light count
    first = pc.first_per_series(runs, descending=True)
    ids = pc.int_list(first.run_id)
    cmds = pc.query(db, "SELECT run_id, scope, name, value FROM stats WHERE run_id IN (%s) AND scope GLOB '*/timing' "
                        "AND scope <> 'frame/timing' AND name IN ('start_cycle', 'binning_end_cycle', 'end_cycle')" % ids)
    frame = pc.query(db, "SELECT run_id, cycles, frame_time_ms FROM v_run_summary WHERE run_id IN (%s)" % ids)
    units = pc.query(db, "SELECT run_id, substr(scope, 12) AS unit, name, value FROM stats WHERE run_id IN (%s) AND "
                         "scope > 'frame/unit.' AND scope < 'frame/unit/' AND name IN ('busy_cycles', 'stalled_cycles')"
                     % ids)
    if cmds.empty or frame.cycles.isna().all():
        pc.fail("--db %s: the selected runs have no per-pass timing (runs written before the timing model)" % args.db)
    ms_per_cycle = (frame.frame_time_ms / frame.cycles).set_axis(frame.run_id)
    cycles = frame.cycles.set_axis(frame.run_id)
    cmds = cmds.pivot_table(index=["run_id", "scope"], columns="name", values="value").reset_index()
    cmds["command"] = cmds.scope.str.replace("/timing", "", regex=False)
    cmds["index"] = [int(m.group(1)) if m else 0 for m in (re.match(r"\D+(\d+)", c) for c in cmds.command)]
    unit_names = pc.ordered(units.unit.unique(), pc.UNITS)

    n = len(first)
    longest = max(cycles[i] * ms_per_cycle[i] for i in first.run_id) if args.ms else 100.0
    fig, (tl, ub) = plt.subplots(1, 2, figsize=(15, ROW_HEIGHT * n * 1.6 + 2.4), gridspec_kw={"width_ratios": [1.6, 1]})
    widest = 0.0
    names = []  # (pass name annotation, bar start, bar end) on the timeline
    for row, r in first.iterrows():
        # x per cycle: ms, or percent of this run's frame
        k = ms_per_cycle[r.run_id] if args.ms else 100.0 / cycles[r.run_id]
        if not args.ms:
            tl.annotate("%.3g ms" % (cycles[r.run_id] * ms_per_cycle[r.run_id]), (101.0, row), va="center", fontsize=7)
        c = cmds[cmds.run_id == r.run_id].sort_values(["start_cycle", "index"])
        for _, cmd in c.iterrows():
            name = cmd.command.split(".", 1)[-1]
            if cmd.command.startswith("dispatch"):
                spans = [("compute", cmd.start_cycle, cmd.end_cycle, row - 0.35, 0.4)]
            else:
                be = cmd.get("binning_end_cycle", cmd.start_cycle)
                spans = [("binning", cmd.start_cycle, be, row + 0.08, 0.3), ("tiles", be, cmd.end_cycle, row - 0.35, 0.4)]
            for phase, a, b, y, h in spans:
                if b <= a:
                    continue
                tl.broken_barh([(a * k, (b - a) * k)], (y, h), facecolor=pc.PHASE_COLORS[phase], edgecolor="black",
                               linewidth=0.5)
                if (b - a) * k > LABEL_MIN_SHARE * longest:
                    names.append((tl.annotate(name, ((a + b) / 2 * k, y + h / 2), ha="center", va="center",
                                              fontsize=6), a * k, b * k))
        u = units[units.run_id == r.run_id].pivot(index="unit", columns="name", values="value")
        h = 0.8 / max(1, len(unit_names))
        for j, un in enumerate(unit_names):
            if un not in u.index:
                continue
            y = row + 0.4 - (j + 0.5) * h
            busy = 100.0 * u.at[un, "busy_cycles"] / cycles[r.run_id]
            stalled = 100.0 * u.at[un, "stalled_cycles"] / cycles[r.run_id]
            col = pc.color(pc.UNIT_COLORS, un)
            ub.barh(y, busy, height=h, color=col, label=un if row == n - 1 else None)
            widest = max(widest, busy + stalled)
            ub.barh(y, stalled, left=busy, height=h, color=col, alpha=0.35, hatch="///", edgecolor="white",
                    linewidth=0)
    for ax in (tl, ub):
        ax.set_yticks(range(n))
        ax.set_ylim(-0.6, n - 0.4)
        ax.grid(axis="x", alpha=0.3)
    tl.set_yticklabels(["%s\n(run %d)" % (sr, i) for sr, i in zip(first.series, first.run_id)], fontsize=8)
    ub.set_yticklabels([])
    tl.set_xlabel("time in the frame (ms)" if args.ms else "time in the frame (% of each frame's time, written at its right)")
    if not args.ms:
        tl.set_xlim(-1.0, 112.0)
    ub.set_xlim(0.0, widest * 1.04)
    tl.set_title("timeline of each pass: binning (upper lane), tile work or compute (lower lane)", fontsize=9)
    ub.set_xlabel("share of the frame's cycles (%): busy (solid), stalled (hatched)")
    ub.set_title("units", fontsize=9)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in pc.PHASE_COLORS.values()]
    fig.legend(handles, ["binning (geometry)", "tile work (first to last tile)", "compute dispatch"], fontsize=7,
               loc="lower left", bbox_to_anchor=(0.08, 0.0), ncol=3)
    uh, ul = ub.get_legend_handles_labels()
    fig.legend(uh, ul, fontsize=7, loc="lower right", ncol=4)
    fig.suptitle("Time by pass and unit\n%s" % pc.title_line(fixed), fontsize=10)
    fig.tight_layout(rect=(0, 0.45 / fig.get_figheight(), 1, 1))
    fit_names(fig, tl, names)
    pc.save(fig, args.out, "%d runs drawn" % n)


if __name__ == "__main__":
    pc.run(main)
