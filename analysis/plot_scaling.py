#!/usr/bin/python3
"""Scaling with the light count: a figure (--metric, default frame_time_ms) against the number of
lights, one line per technique (and variant), a panel per configuration in the selection.

Reads a tbdrsim results database through its views (v_run_summary, v_metric): finished runs only.
Different scenes or frame sizes are refused (pick one with --scene / --where); runs of one
technique from different traces at one light count (technique options, seeds) are separate
lines; only repetitions are averaged. Log-log axes with plain tick labels when the range is wide.

    tbdrsim plot scaling --db study/study.db --metric frame_time_ms --out scaling.png
    /usr/bin/python3 analysis/plot_scaling.py --db out/lights.db --metric dram_total_mb --config series6xt_gx6450
"""
import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

#: Light counts spanning this factor or more get a log2 x axis (doubling steps read evenly).
LOG_LIGHTS_RANGE = 4.0


def main():
    args, db, runs = pc.open_selection(
        __doc__, "scaling.png",
        pc.metric_option("frame_time_ms", "lights_per_pixel, dram_total_mb, energy_total_mj, tsp.light_evaluations, ..."),
        pc.flag("--linear", "linear axes (default: log-log when the range is wide)"))
    panels, fixed = pc.facets(runs, shown=("lights",), facet=("config",), max_panels=6)
    vals = pc.metric_values(db, runs, args.metric)
    unit = vals.unit.iloc[0]
    g = pc.average(runs, vals, ["config", "technique", "variant", "series", "lights"])
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(7.0 * n + 2.8, 5.5), squeeze=False)
    handles = {}
    for ax, (ptitle, pr) in zip(axes[0], panels):
        p = g[g.config.isin(pr.config.unique())]
        for tech in pc.ordered(p.technique.unique(), pc.TECHNIQUES):
            t = p[p.technique == tech]
            for vi, var in enumerate(sorted(t.variant.unique())):
                s = t[t.variant == var].sort_values("lights")
                (line,) = ax.plot(s.lights.astype(float), s.value, label=s.series.iloc[0],
                                  **pc.technique_style(tech, vi))
                handles.setdefault(s.series.iloc[0], line)
        lights = sorted(p.lights.astype(float).unique())
        if not args.linear and len(lights) > 1 and lights[-1] >= LOG_LIGHTS_RANGE * max(1.0, lights[0]):
            pc.log_axis(ax, "x", lights, base=2)
            values = p.value if args.independent_y else g.value  # a shared y axis spans every panel
            if pc.wide_range(values, pc.LOG_RANGE):
                pc.log_axis(ax, "y", values)
        else:
            ax.set_xticks(lights)
            ax.set_xticklabels(["%d" % v for v in lights])
        ax.set_xlabel("lights in the scene (count)")
        ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
        ax.grid(alpha=0.3, which="both")
        if ptitle:
            ax.set_title(ptitle, fontsize=9)
    pc.share_y(axes[0], args)
    note = pc.repetition_note(runs)
    fig.suptitle("%s against the light count\n%s%s" % (args.metric, pc.title_line(fixed),
                                                         "\n(" + note + ")" if note else ""), fontsize=10)
    fig.legend(list(handles.values()), list(handles.keys()), fontsize=8, loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - 2.8 / fig.get_figwidth(), 1))
    pc.save(fig, args.out, "%d runs, %d series, %d light counts, %d panel(s)"
            % (len(runs), runs.series.nunique(), runs.lights.nunique(), n))


if __name__ == "__main__":
    pc.run(main)
