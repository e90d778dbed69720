#!/usr/bin/python3
"""Technique comparison: one bar per technique (and variant) for a figure (--metric, e.g.
frame_time_ms), a panel per configuration and light count in the selection; or, by default
(--metric dram_classes), DRAM MB stacked by traffic class (the `dram` plot, plot_dram.py).

Reads a tbdrsim results database through its views (v_run_summary, v_metric): finished runs only.
Runs of different configurations or light counts get their own panels; different scenes or frame
sizes are refused (pick one with --scene / --where); runs of one technique from different traces
are separate bars; only repetitions are averaged (whiskers span their min..max).

    tbdrsim plot techniques --db study/study.db --metric frame_time_ms --out techniques.png
    /usr/bin/python3 analysis/plot_techniques.py --db out/techniques.db --metric energy_total_mj --lights 1024
"""
import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt


def main():
    args, db, runs = pc.open_selection(
        __doc__, "techniques.png",
        pc.option("--metric", default="dram_classes",
                  help="a v_metric name (frame_time_ms, cycles, dram_total_mb, energy_total_mj, overshading, ...) "
                       "or dram_classes (default: DRAM MB stacked by class, plot_dram.py)"),
        pc.flag("--log", "log y axis (default: linear; bars start at zero)"))
    if args.metric == "dram_classes":
        import plot_dram
        return plot_dram.draw(args, db, runs)
    panels, fixed = pc.facets(runs, facet=("config", "lights"))
    vals = pc.metric_values(db, runs, args.metric)
    unit = vals.unit.iloc[0]
    n = len(panels)
    fig, axes = pc.bar_panels(panels, runs, 5.0)
    for ax, (ptitle, pr) in zip(axes.flat, panels):
        d = vals.merge(pr, on="run_id")
        g = d.groupby(["technique", "series"]).value.agg(["mean", "min", "max"]).reset_index().sort_values("mean")
        x = range(len(g))
        ax.bar(x, g["mean"], yerr=[g["mean"] - g["min"], g["max"] - g["mean"]], capsize=3, width=0.7,
               color=[pc.color(pc.TECHNIQUE_COLORS, t) for t in g.technique])
        for i, v in zip(x, g["mean"]):
            ax.annotate("%.3g" % v, (i, v), ha="center", va="bottom", fontsize=7)
        ax.set_xticks(list(x))
        ax.set_xticklabels(g.series, rotation=35, ha="right", fontsize=8)
        ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
        if args.log and args.independent_y:
            pc.log_axis(ax, "y", g["mean"])
        ax.grid(axis="y", alpha=0.3)
        if ptitle:
            ax.set_title(ptitle, fontsize=9)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    pc.share_y(axes.flat, args)
    if args.log and not args.independent_y:
        pc.log_axis(axes.flat[0], "y", vals.value)
    note = pc.repetition_note(runs)
    fig.suptitle("%s per technique\n%s%s" % (args.metric, pc.title_line(fixed), "\n(" + note + ")" if note else ""),
                 fontsize=10)
    fig.tight_layout()
    pc.save(fig, args.out, "%d runs, %d series, %d panel(s)" % (len(runs), runs.series.nunique(), n))


if __name__ == "__main__":
    pc.run(main)
