#!/usr/bin/python3
"""Sensitivity: a figure (--metric) against hardware parameters, a column of panels per parameter,
one line per technique (and variant). By default the tile size (tiling.tile_width) and the on-chip
tile memory budget (pls.tile_buffer_bits_per_pixel), those of them the selection varies; any
parameter key of `tbdrsim params` works (--param, repeatable), and so do the keys report --by
takes: a technique option (technique.pls_bytes: the runs of techniques that have it) or a trace key.

Reads a tbdrsim results database through v_run_summary, v_param and v_metric (finished runs).
Nothing else is averaged away: every other parameter the selection varies, and the light count,
give a row of panels per value (fix one with --fix KEY=VALUE, or --lights); different scenes or
frame sizes are refused; runs of one technique from different traces are separate lines; only
repetitions are averaged.

    tbdrsim plot sensitivity --db out/tile_size.db --metric frame_time_ms --out sensitivity.png
    /usr/bin/python3 analysis/plot_sensitivity.py --db out/tile_size.db --param tiling.tile_width \\
        --fix pls.tile_buffer_bits_per_pixel=128
"""
import re
import textwrap

import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt
pd = pc.pd

DEFAULT_PARAMS = ["tiling.tile_width", "pls.tile_buffer_bits_per_pixel"]
#: Parameters that vary with another one by construction (a square tile's height with its width):
#: shown in the panel title, not as rows.
TIED = {"tiling.tile_width": ["tiling.tile_height"], "tiling.tile_height": ["tiling.tile_width"]}
#: Characters of a panel's title per line (9-point text over a 6.2-inch panel).
ROW_TITLE_CHARS = 80
#: At most this many rows of panels per parameter; more means the selection varies too much.
MAX_ROWS = 6


def main():
    args, db, runs = pc.open_selection(
        __doc__, "sensitivity.png",
        pc.metric_option("frame_time_ms", "dram_total_mb, energy_total_mj, dram_spill_mb, ..."),
        pc.option("--param", action="append",
                  help="parameter key for the x axis; repeatable (default: %s)" % " and ".join(DEFAULT_PARAMS)),
        pc.flag("--linear", "linear y axis (default: log when values span > 20x)"))
    extra = [k for k in args.param or [] if k.split(".")[0] in ("technique", "trace", "config")]
    wide, num = pc.hardware_params(db, runs, extra)
    varying = [k for k in wide.columns if k not in extra and wide[k].nunique() > 1]
    if args.param:
        for k in args.param:
            if k not in wide.columns:
                pc.fail("--param %s: not a parameter of the selected runs (a `tbdrsim params` key, technique.<option> "
                        "or trace.<key>, as report --by takes)" % k)
        params = args.param
    else:
        params = [k for k in DEFAULT_PARAMS if k in varying]
        if not params:
            pc.fail("neither %s varies in the selection; name the swept parameter with --param (varying: %s)"
                    % (" nor ".join(DEFAULT_PARAMS), ", ".join(varying) or "none"))
    _, fixed = pc.facets(runs, shown=("config", "lights"))  # refuses mixed scenes and frame sizes
    vals = pc.metric_values(db, runs, args.metric)
    unit = vals.unit.iloc[0]
    data = vals.merge(runs, on="run_id").set_index("run_id")

    layout = []  # per parameter: [(row title, runs of the row)]
    for key in params:
        have = wide[key].notna()
        if not have.all():
            without = runs[~have.values]
            pc.note("left out of %s: %d run(s) without it (%s)" % (
                key, len(without), ", ".join(pc.ordered(without.technique.unique(), pc.TECHNIQUES))))
        others = [k for k in varying if k != key and k not in TIED.get(key, [])]
        if runs.lights.nunique() > 1:
            others.append("lights")
        # Configurations that the parameters varying (the x axis's among them) do not tell apart.
        told = [k for k in others + [key] + TIED.get(key, []) if k in wide.columns]
        by_run = runs.set_index("run_id")
        if by_run.config[have.values].groupby([wide[k][have] for k in told]).nunique().max() > 1:
            others.append("config")
        # Numbers as numbers, so that rows come in numeric order (64 before 128).
        frame = wide.copy()
        for k in frame.columns:
            if num[k].notna().all():
                frame[k] = num[k]
        frame = frame.assign(lights=runs.set_index("run_id").lights.astype(int),
                             config=runs.set_index("run_id").config)[have.values]
        rows = [("", frame.index)] if not others else \
            [(", ".join("%s=%g" % (k, v) if isinstance(v, float) else "%s=%s" % (k, v)
                        for k, v in zip(others, combo if isinstance(combo, tuple) else (combo,))), g.index)
             for combo, g in frame.groupby(others if len(others) > 1 else others[0])]
        if len(rows) > MAX_ROWS:
            pc.fail("%s varies with %s: %d rows of panels; fix some with --fix KEY=VALUE or --lights"
                    % (key, ", ".join(others), len(rows)))
        layout.append(rows)
    nrows = max(len(r) for r in layout)
    fig, axes = plt.subplots(nrows, len(params), figsize=(6.2 * len(params) + 2.8, 4.2 * nrows), squeeze=False)
    handles = {}
    values = []
    for col, (key, rows) in enumerate(zip(params, layout)):
        have = wide[key].notna()
        numeric = num[key][have].notna().all()
        xs = sorted(num[key][have].unique()) if numeric else sorted(wide[key][have].unique(), key=pc.natural)
        # A technique option on x is what the line follows, not what tells its series apart.
        strip = re.compile(r"(^| )%s=\S+" % re.escape(key[len("technique."):])) if key.startswith("technique.") else None
        for row in range(nrows):
            ax = axes[row, col]
            if row >= len(rows):
                ax.set_visible(False)
                continue
            rtitle, rids = rows[row]
            d = data.loc[data.index.intersection(rids)].copy()
            d["x"] = num.loc[d.index, key] if numeric else wide.loc[d.index, key].map(xs.index)
            if strip:
                d["variant"] = [strip.sub("", v).strip() for v in d.variant]
                d["series"] = [t + (" " + v if v else "") for t, v in zip(d.technique, d.variant)]
            g = d.groupby(["technique", "variant", "series", "x"]).value.mean().reset_index()
            values += list(g.value)
            for tech in pc.ordered(g.technique.unique(), pc.TECHNIQUES):
                t = g[g.technique == tech]
                for vi, var in enumerate(sorted(t.variant.unique())):
                    s = t[t.variant == var].sort_values("x")
                    (line,) = ax.plot(s.x, s.value, label=s.series.iloc[0], **pc.technique_style(tech, vi))
                    handles.setdefault(s.series.iloc[0], line)
            if numeric and len(xs) > 1 and xs[0] > 0 and xs[-1] / xs[0] >= 4:
                pc.log_axis(ax, "x", xs, base=2)
            else:
                ax.set_xticks(xs if numeric else range(len(xs)))
                ax.set_xticklabels(["%g" % v for v in xs] if numeric else xs)
            tied = [k for k in TIED.get(key, []) if k in varying]
            ax.set_xlabel(key + (" (and " + ", ".join(tied) + ")" if tied else ""))
            ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
            ax.grid(alpha=0.3, which="both")
            ax.set_title(textwrap.fill(rtitle or ("%s vs %s" % (args.metric, key)), ROW_TITLE_CHARS), fontsize=9)
    visible = [ax for ax in axes.flat if ax.get_visible()]
    pc.share_y(visible, args)
    if not args.linear:
        for ax in visible if args.independent_y else visible[:1]:
            v = [ln.get_ydata() for ln in ax.get_lines()]
            v = [y for ys in (v if args.independent_y else [values]) for y in ys]
            if pc.wide_range(v, pc.LOG_RANGE):
                pc.log_axis(ax, "y", v)
    note = pc.repetition_note(runs)
    shared = pc.title_line([f for f in fixed if f[0] in ("scene", "frame")] +
                           [("config", pc.common_config(runs))] +
                           ([("lights", runs.lights.iloc[0])] if runs.lights.nunique() == 1 else []),
                           ["fixed: " + ", ".join(args.fix)] if args.fix else [])
    fig.suptitle("Sensitivity of %s\n%s%s" % (args.metric, shared, "\n(" + note + ")" if note else ""), fontsize=10)
    fig.legend(list(handles.values()), list(handles.keys()), fontsize=8, loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - 2.8 / fig.get_figwidth(), 1))
    pc.save(fig, args.out, "%d runs, %d series, %d parameter(s), %d row(s)"
            % (len(runs), runs.series.nunique(), len(params), nrows))


if __name__ == "__main__":
    pc.run(main)
