#!/usr/bin/python3
"""Scaling with the light count: a metric against the number of lights, one line per technique.

Reads a tbdrsim results database through its views (v_metric for the figure, v_param's
trace.lights for the light count): finished runs only, repetitions and every other run at the same
light count averaged. Narrow the selection with --where (SQL on v_run_summary's columns) or
--config.

Run with Debian's interpreter, which has pandas and matplotlib (scripts/install_deps.sh):
    /usr/bin/python3 analysis/plot_scaling.py --db out/lights.db --metric frame_time_ms --out scaling.png
    /usr/bin/python3 analysis/plot_scaling.py --db out/lights.db --metric dram_total_mb --where "config_name = 'x'"
"""
import argparse
import sys

import plot_common  # first: it selects matplotlib's file-only backend before pyplot loads

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    plot_common.add_common_args(ap, "scaling.png", "frame_time_ms",
                                "a v_metric name (default frame_time_ms; lights_per_pixel, dram_total_mb, "
                                "energy_total_mj, tsp.light_evaluations, ...)")
    plot_common.add_selection_args(ap)
    ap.add_argument("--linear", action="store_true", help="linear axes (default: log-log when the range is wide)")
    args = ap.parse_args()

    db = plot_common.connect(args.db)
    where, caption = plot_common.selection(args, "s")
    d = pd.read_sql_query(
        "SELECT s.run_id, s.technique, p.value_num AS lights, m.value, m.unit "
        "FROM v_run_summary s JOIN v_param p ON p.run_id = s.run_id AND p.key = 'trace.lights' "
        "JOIN v_metric m ON m.run_id = s.run_id AND m.metric = ? WHERE " + where,
        db, params=(args.metric,))
    d = d.dropna(subset=["value", "lights"])
    if d.empty:
        sys.exit("plot_scaling: no finished run has the figure '%s'%s" %
                 (args.metric, " with " + ", ".join(caption) if caption else ""))
    unit = d.unit.iloc[0]
    g = d.groupby(["technique", "lights"]).value.mean().reset_index()
    fig, ax = plt.subplots(figsize=(8, 5.5))
    last = g.sort_values("lights").groupby("technique").value.last().sort_values(ascending=False)
    for i, tech in enumerate(last.index):
        t = g[g.technique == tech].sort_values("lights")
        ax.plot(t.lights, t.value, label=tech, **plot_common.technique_style(i))
    wide = g.lights.max() >= 4 * max(1.0, g.lights.min())
    if wide and not args.linear:
        ax.set_xscale("log", base=2)
        if (g.value > 0).all():
            ax.set_yscale("log")
    ax.set_xticks(sorted(g.lights.unique()))
    ax.set_xticklabels([str(int(v)) for v in sorted(g.lights.unique())])
    ax.set_xlabel("lights in the scene (count)")
    ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
    ax.set_title("%s against the light count%s\n(mean over repetitions and other runs at each count)"
                 % (args.metric, "\n" + ", ".join(caption) if caption else ""), fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print("wrote %s (%d runs, %d techniques, %d light counts)" %
          (args.out, d.run_id.nunique(), g.technique.nunique(), g.lights.nunique()))


if __name__ == "__main__":
    main()
