#!/usr/bin/python3
"""Technique comparison: one bar per technique, DRAM MB stacked by traffic class (default), or one
metric per technique (--metric frame_time_ms, energy_total_mj, ...).

Reads a tbdrsim results database through its views (v_dram_class, v_metric, v_run_summary):
finished runs only, repetitions and every other run in the selection averaged per technique.
Narrow the selection with --where (SQL on v_run_summary's columns), --config or --lights.

Run with Debian's interpreter, which has pandas and matplotlib (scripts/install_deps.sh):
    /usr/bin/python3 analysis/plot_techniques.py --db out/techniques.db --out techniques.png
    /usr/bin/python3 analysis/plot_techniques.py --db out/techniques.db --metric frame_time_ms --lights 1024
"""
import argparse
import sys

import plot_common  # first: it selects matplotlib's file-only backend before pyplot loads

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

# The simulator's traffic classes, in its order (sim: models/traffic.hpp); others follow.
CLASS_ORDER = ["parameter_buffer", "vertices", "indices", "textures", "color", "depth_stencil", "gbuffer",
               "visibility", "light_data", "light_lists", "work_lists", "spill", "other"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    plot_common.add_common_args(ap, "techniques.png", "dram_classes",
                                "dram_classes (stacked DRAM MB per class, default) or a v_metric name "
                                "(frame_time_ms, cycles, energy_total_mj, overshading, ...)",
                                "SQL condition on v_run_summary's columns, e.g. \"lights = 256\"")
    plot_common.add_selection_args(ap, lights=True)
    args = ap.parse_args()

    db = plot_common.connect(args.db)
    where, captions = plot_common.selection(args)
    caption = ", ".join(captions)
    runs = pd.read_sql_query("SELECT run_id, technique, config_hash, lights, scene FROM v_run_summary WHERE " + where,
                             db)
    if runs.empty:
        sys.exit("plot_techniques: no finished run matches (%s)" % (caption or "all runs"))
    ids = ",".join(str(i) for i in runs.run_id)
    mixed = runs.groupby("technique")[["config_hash", "lights", "scene"]].nunique().max().max() > 1
    note = "mean over " + ("several configurations, light counts or scenes; narrow with --where" if mixed
                           else "repetitions")

    fig, ax = plt.subplots(figsize=(max(6.0, 0.75 * runs.technique.nunique() + 3), 5.5))
    if args.metric == "dram_classes":
        d = pd.read_sql_query("SELECT run_id, technique, class, total_mb FROM v_dram_class "
                              "WHERE run_id IN (%s)" % ids, db)
        table = d.groupby(["technique", "class"]).total_mb.mean().unstack(fill_value=0.0)
        table = table.loc[:, table.sum() > 0]
        cols = [c for c in CLASS_ORDER if c in table.columns] + sorted(c for c in table.columns if c not in CLASS_ORDER)
        table = table[cols]
        table = table.loc[table.sum(axis=1).sort_values().index]
        table.plot.bar(stacked=True, ax=ax, width=0.75, colormap="tab20")
        ax.set_ylabel("DRAM traffic (MB, read + written)")
        ax.legend(title="traffic class", fontsize=8, title_fontsize=9, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        title = "DRAM traffic per technique by class"
        for i, total in enumerate(table.sum(axis=1)):
            ax.annotate("%.1f" % total, (i, total), ha="center", va="bottom", fontsize=7)
    else:
        d = pd.read_sql_query("SELECT run_id, metric, value, unit FROM v_metric WHERE metric = ? AND run_id IN (%s)"
                              % ids, db, params=(args.metric,))
        d = d.dropna(subset=["value"])
        if d.empty:
            sys.exit("plot_techniques: no selected run has the figure '%s' (SELECT DISTINCT metric FROM v_metric)"
                     % args.metric)
        unit = d.unit.iloc[0]
        d = d.merge(runs[["run_id", "technique"]], on="run_id")
        g = d.groupby("technique").value.agg(["mean", "min", "max"]).sort_values("mean")
        ax.bar(range(len(g)), g["mean"], yerr=[g["mean"] - g["min"], g["max"] - g["mean"]], capsize=3,
               color="tab:blue", width=0.7)
        ax.set_xticks(range(len(g)))
        ax.set_xticklabels(g.index)
        ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
        title = "%s per technique" % args.metric
        note += "; bars span min..max"
    ax.set_xlabel("technique")
    ax.set_title(title + ("\n" + caption if caption else "") + "\n(" + note + ")", fontsize=10)
    plt.setp(ax.get_xticklabels(), rotation=35, ha="right")
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print("wrote %s (%d runs, %d techniques)" % (args.out, len(runs), runs.technique.nunique()))


if __name__ == "__main__":
    main()
