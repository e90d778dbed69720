#!/usr/bin/python3
"""Sensitivity: a metric against hardware parameters, one panel per parameter, one line per
technique. By default the tile size (tiling.tile_width) and the on-chip tile memory budget
(pls.tile_buffer_bits_per_pixel); any parameter key of `tbdrsim params` works (--param, repeatable).

Reads a tbdrsim results database through v_sensitivity (finished runs; a parameter's value and a
figure per row). At each parameter value, runs that differ in other parameters or repetitions
are averaged; fix the others with --where (SQL on v_run_summary's columns, or
"run_id IN (SELECT run_id FROM v_param WHERE key = '...' AND value = '...')").

Run with Debian's interpreter, which has pandas and matplotlib (scripts/install_deps.sh):
    /usr/bin/python3 analysis/plot_sensitivity.py --db out/tile_size.db --metric frame_time_ms
    /usr/bin/python3 analysis/plot_sensitivity.py --db out/tile_size.db --param isp.tag_buffers --metric cycles
"""
import argparse
import sys

import plot_common  # first: it selects matplotlib's file-only backend before pyplot loads

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

# Units of the parameters users sweep most (the full list: `tbdrsim params`).
PARAM_UNITS = {
    "tiling.tile_width": "pixels", "tiling.tile_height": "pixels",
    "pls.tile_buffer_bits_per_pixel": "bits/pixel", "pls.max_pls_bytes_per_pixel": "bytes/pixel",
    "isp.tag_buffers": "buffers", "isp.tiles_in_flight": "tiles", "isp.samples_per_clock": "samples/clock",
    "usc.count": "USCs", "gpu.core_clock_mhz": "MHz", "dram.bandwidth_gbps": "GB/s", "trace.lights": "lights",
    "tiling.pb_capacity_bytes": "bytes", "cache.slc.size_bytes": "bytes", "writeback.compression_ratio": "ratio",
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    plot_common.add_common_args(ap, "sensitivity.png", "frame_time_ms",
                                "a v_metric name (default frame_time_ms; dram_total_mb, energy_total_mj, dram_spill_mb, ...)")
    ap.add_argument("--param", action="append",
                    help="parameter key for the x axis; repeatable "
                         "(default: tiling.tile_width and pls.tile_buffer_bits_per_pixel)")
    ap.add_argument("--linear", action="store_true", help="linear y axis (default: log when values span > 20x)")
    args = ap.parse_args()
    params = args.param or ["tiling.tile_width", "pls.tile_buffer_bits_per_pixel"]

    db = plot_common.connect(args.db)
    cond = ""
    if args.where:
        cond = " AND run_id IN (SELECT run_id FROM v_run_summary WHERE " + args.where + ")"
    fig, axes = plt.subplots(1, len(params), figsize=(6.5 * len(params), 5.2), squeeze=False)
    handles = {}
    plotted = 0
    techniques = sorted(r[0] for r in db.execute(
        "SELECT DISTINCT technique FROM runs WHERE status = 'ok'" + cond.replace(" AND run_id IN", " AND id IN")))
    unit = ""
    for ax, key in zip(axes[0], params):
        d = pd.read_sql_query("SELECT run_id, technique, value_num, metric_value, metric_unit FROM v_sensitivity "
                              "WHERE key = ? AND metric = ?" + cond, db, params=(key, args.metric))
        d = d.dropna(subset=["value_num", "metric_value"])
        ax.set_xlabel("%s (%s)" % (key, PARAM_UNITS[key]) if key in PARAM_UNITS else key)
        if d.empty:
            ax.text(0.5, 0.5, "no finished run with %s\nand %s" % (key, args.metric), ha="center", va="center",
                    transform=ax.transAxes)
            continue
        unit = d.metric_unit.iloc[0]
        ax.set_ylabel("%s (%s)" % (args.metric, unit) if unit else args.metric)
        g = d.groupby(["technique", "value_num"]).metric_value.mean().reset_index()
        values = sorted(g.value_num.unique())
        for tech in sorted(g.technique.unique()):
            t = g[g.technique == tech].sort_values("value_num")
            i = techniques.index(tech)  # the same colour and marker in every panel
            (line,) = ax.plot(t.value_num, t.metric_value, label=tech, **plot_common.technique_style(i))
            handles.setdefault(tech, line)
        positive = g.metric_value[g.metric_value > 0]
        if not args.linear and len(positive) == len(g) and positive.max() > 20 * positive.min():
            ax.set_yscale("log")
        if len(values) > 1 and values[0] > 0 and values[-1] / values[0] >= 4:
            ax.set_xscale("log", base=2)
        ax.set_xticks(values)
        ax.set_xticklabels(["%g" % v for v in values])
        ax.minorticks_off()
        ax.grid(alpha=0.3)
        ax.set_title("%s vs %s (%d values)" % (args.metric, key, len(values)), fontsize=10)
        plotted += 1
    if not plotted:
        sys.exit("plot_sensitivity: no finished run has '%s' against %s" % (args.metric, ", ".join(params)))
    fig.suptitle("Sensitivity of %s%s (other parameters and repetitions averaged)" %
                 (args.metric, "; " + args.where if args.where else ""), fontsize=11)
    fig.legend(handles.values(), handles.keys(), fontsize=8, loc="center right")
    fig.tight_layout(rect=(0, 0, 0.83, 1))
    fig.savefig(args.out, dpi=120)
    print("wrote %s (%d panel(s), %d techniques)" % (args.out, plotted, len(handles)))


if __name__ == "__main__":
    main()
