#!/usr/bin/python3
"""Delta versus a baseline: how much a figure (--metric, default frame_time_ms) changes, in percent
(or as a ratio with --ratio), when one thing changes from a baseline value, each run compared with
its own baseline run (the same technique, trace and every other parameter).

--baseline KEY=VALUE names the baseline: a parameter key (`tbdrsim params`; e.g.
pls.tile_buffer_bits_per_pixel=128: every other budget against 128 bits/pixel), a technique option
(technique.pls_bytes=16, when the database stores them), config=NAME (configurations against one),
or technique=NAME (every technique against one, per configuration and light count). Bars: one
group per technique (and variant), one bar per non-baseline value, a panel per light count (and
configuration, for technique=). Runs without a baseline partner are left out and counted; other
parameters that vary are refused (fix them with --fix KEY=VALUE, or --where).

    tbdrsim plot delta --db out/pls_budget.db --baseline pls.tile_buffer_bits_per_pixel=128 --out delta.png
    tbdrsim plot delta --db study/study.db --baseline technique=deferred --metric dram_total_mb
"""
import re

import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

#: Inches of legend per character of its longest label (7-point text).
LEGEND_INCH_PER_CHAR = 0.055
pd = pc.pd


def main():
    ap = pc.parser(__doc__, "delta.png")
    ap.add_argument("--baseline", required=True, metavar="KEY=VALUE",
                    help="the baseline: a parameter key, technique.<option>, config=NAME or technique=NAME")
    names, kwargs = pc.metric_option("frame_time_ms", "dram_total_mb, energy_total_mj, ...")
    ap.add_argument(*names, **kwargs)
    ap.add_argument("--ratio", action="store_true", help="bars as value / baseline instead of percent change")
    args = ap.parse_args()
    key, sep, base = args.baseline.partition("=")
    if not sep or not key or not base:
        pc.fail("--baseline %s: expected KEY=VALUE (a parameter key, technique.<option>, config=NAME or "
                "technique=NAME)" % args.baseline)

    db = pc.connect(args.db)
    runs = pc.load_runs(db, args)
    wide, num = pc.hardware_params(db, runs, [key])
    runs = runs.set_index("run_id", drop=False)

    if key == "technique":
        runs["value"] = runs.technique
        match = ["config_hash", "scene", "frame", "lights"]
        group, facet = "value", ("config", "lights")
    elif key == "config":
        # Configurations by label (what the messages list); a preset's name when it names one.
        if base not in set(runs.config) and base in set(runs.config_name):
            labels = sorted(runs.config[runs.config_name == base].unique())
            if len(labels) > 1:
                pc.fail("--baseline %s: %d configurations are of the preset %s (%s); name one by its label"
                        % (args.baseline, len(labels), base, "; ".join(labels)))
            base = labels[0]
        runs["value"] = runs.config
        match = ["trace_hash"]
        group, facet = "series", ("lights",)
    elif key.startswith("technique."):
        opts = pc.query(db, "SELECT run_id, value FROM v_param WHERE key = ? AND run_id IN (%s)"
                        % pc.int_list(runs.run_id), params=(key,)).set_index("run_id").value
        if opts.empty:
            pc.fail("--baseline %s: no selected run stores the technique option %s" % (args.baseline, key))
        without = runs[~runs.run_id.isin(opts.index)]
        if not without.empty:
            pc.note("left out: %d run(s) of techniques without the option %s (%s)"
                    % (len(without), key, ", ".join(pc.ordered(without.technique.unique(), pc.TECHNIQUES))))
        runs = runs[runs.run_id.isin(opts.index)].copy()
        runs["value"] = opts.reindex(runs.run_id).values
        # A series is the technique and its other options: the option is what the bars compare.
        strip = re.compile(r"(^| )%s=\S+" % re.escape(key[len("technique."):]))
        runs["variant"] = [strip.sub("", v).strip() for v in runs.variant]
        runs["series"] = [t + (" " + v if v else "") for t, v in zip(runs.technique, runs.variant)]
        match = ["technique", "config_hash", "scene", "frame", "lights"]
        group, facet = "series", ("config", "lights")
    else:
        if key not in wide.columns:
            pc.fail("--baseline %s: %s is not a parameter of the selected runs (tbdrsim params lists them)"
                    % (args.baseline, key))
        runs["value"] = wide[key]
        match = ["trace_hash"]
        group, facet = "series", ("lights",)
        # Parameters that vary with the key (a zipped tile height) are part of what changes; any
        # other that varies would be averaged over: refuse.
        varying = []
        for k in wide.columns:
            if k == key or wide[k].nunique() <= 1:
                continue
            if wide.groupby(wide[key])[k].nunique().max() <= 1:
                continue
            varying.append("%s (%s)" % (k, ", ".join(sorted(wide[k].unique()))))
        if varying:
            pc.fail("other parameters vary in the selection and would be averaged: %s; fix them with --fix KEY=VALUE "
                    "or --where" % "; ".join(varying))
        if runs.config_name.nunique() > 1:
            pc.fail("the selection holds several configuration presets (%s); pick one with --config"
                    % ", ".join(sorted(runs.config_name.unique())))
    values = runs.value.dropna().unique()
    is_base = (runs.value == base) | (pd.to_numeric(runs.value, errors="coerce") == pd.to_numeric(base, errors="coerce"))
    if not is_base.any():
        pc.fail("--baseline %s: no selected run has %s = %s (they have %s)"
                % (args.baseline, key, base, ", ".join(sorted(str(v) for v in values))))
    base_label = runs.value[is_base].iloc[0]
    vals = pc.metric_values(db, runs, args.metric).set_index("run_id")
    unit = vals.unit.iloc[0]
    runs["metric"] = vals.value.reindex(runs.run_id)
    # The key changes the configuration (its label) unless it is the technique or one of its options.
    panels, fixed = pc.facets(runs, shown=("config",) if key == "config" or "." in key and not
                              key.startswith("technique.") else (), facet=facet)
    cmap = plt.get_cmap("viridis")

    def deltas(pr):
        """The panel's points against their baselines: mean of repetitions, then each against the
        baseline point of the same context; and how many points had no baseline partner."""
        cols = list(dict.fromkeys(match + ([] if key == "technique" else ["series"])))
        pts = pr.groupby(list(dict.fromkeys(cols + ["technique", "value"])), dropna=False).metric.mean().reset_index()
        pts["is_base"] = pts.value == base_label
        basev = pts[pts.is_base].groupby(cols, dropna=False).metric.mean()
        pts = pts[~pts.is_base].copy()
        pts["base"] = [basev.get(tuple(r) if len(cols) > 1 else r[0]) for r in pts[cols].itertuples(index=False)]
        missing = int(pts.base.isna().sum())
        pts = pts.dropna(subset=["base"])
        pts["delta"] = pts.metric / pts.base if args.ratio else (pts.metric / pts.base - 1.0) * 100.0
        return pts, missing

    per_panel = [(t, *deltas(pr)) for t, pr in panels]
    unpaired = sum(m for _, _, m in per_panel)
    if all(p.empty for _, p, _ in per_panel):
        pc.fail("no selected run has a baseline partner for %s (the same trace and other parameters)" % args.baseline)
    others = sorted(pd.concat([p.value for _, p, _ in per_panel]).unique(),
                    key=lambda v: (pd.to_numeric(v, errors="coerce"), str(v)))
    ngroups = max(p[group].nunique() for _, p, _ in per_panel)

    n = len(panels)
    width = max(7.0, 0.55 * ngroups * (1 if key == "technique" else len(others) ** 0.5) + 4)
    # The values against the baseline: one legend at the right, beside the panels (not over a bar).
    legend_w = 0.0 if key == "technique" else LEGEND_INCH_PER_CHAR * max(len("%s = %s" % (key, v)) for v in others) + 0.5
    fig, axes = plt.subplots(n, 1, figsize=(width + legend_w, 4.8 * n), squeeze=False)
    if unpaired:
        pc.note("left out: %d point(s) without a baseline partner (the same trace and other parameters at %s = %s)"
                % (unpaired, key, base_label))
    for ax, (ptitle, sel, _) in zip(axes[:, 0], per_panel):
        if key == "technique":
            g = sel.groupby("value")[["delta", "base", "metric"]].mean()
            g = g.loc[pc.ordered(g.index, pc.TECHNIQUES)].sort_values("delta")
            x = range(len(g))
            ax.bar(x, g.delta, width=0.7, color=[pc.color(pc.TECHNIQUE_COLORS, t) for t in g.index])
            labels = list(g.index)
            tops = list(zip(x, g.delta))
        else:
            series = pc.ordered(sel.series.unique(), [])
            w = 0.8 / len(others)
            tops, labels = [], []
            for j, v in enumerate(others):
                s = sel[sel.value == v].set_index("series").reindex(series)
                xs = [i - 0.4 + (j + 0.5) * w for i in range(len(series))]
                ax.bar(xs, s.delta, width=w, color=cmap(j / max(1, len(others) - 1) * 0.85),
                       label="%s = %s" % (key, v))
                tops += list(zip(xs, s.delta))
            x = range(len(series))
            labels = ["%s\n(base %.3g)" % (t, sel[sel.series == t].base.iloc[0]) for t in series]
        for xi, v in tops:
            if pd.notna(v):
                ax.annotate("%+.1f%%" % v if not args.ratio else "%.2fx" % v, (xi, v), ha="center",
                            va="bottom" if (v >= (1 if args.ratio else 0)) else "top", fontsize=6)
        ax.axhline(1.0 if args.ratio else 0.0, color="black", linewidth=0.8)
        ax.set_xticks(list(x))
        ax.set_xticklabels(labels, rotation=35, ha="right", fontsize=7)
        ax.set_ylabel(("%s / baseline" if args.ratio else "change in %s vs baseline (%%)") % args.metric)
        ax.grid(axis="y", alpha=0.3)
        if key == "technique" and not sel.empty:
            ptitle = (ptitle + ": " if ptitle else "") + "%s = %.4g %s" % (base_label, sel.base.iloc[0], unit)
        if ptitle:
            ax.set_title(ptitle, fontsize=9)
    for ax in axes[:, 0]:
        ax.use_sticky_edges = False  # bars stick to 0: the margin goes beyond it too
        ax.margins(y=0.15)  # room for the values written at the bars' ends
    pc.share_y(axes[:, 0], args)
    fig.suptitle("%s against the baseline %s = %s (baseline %s in %s)\n%s"
                 % (args.metric, key, base_label, args.metric, unit,
                    pc.title_line(fixed, ["fixed: " + ", ".join(args.fix)] if args.fix else [])), fontsize=10)
    if legend_w:
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, fontsize=7, loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - legend_w / fig.get_figwidth(), 1))
    pc.save(fig, args.out, "%d comparisons, %d panel(s)" % (sum(len(p) for _, p, _ in per_panel), n))


if __name__ == "__main__":
    pc.run(main)
