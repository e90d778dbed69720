#!/usr/bin/python3
"""DRAM traffic by class for one configuration: one bar per technique (and variant), MB read +
written at the DRAM devices (after the texture, vertex and system level caches) stacked by the
traffic class that caused it, and a black tick at what the units requested at the chip boundary
before those caches. A panel per light count.

Reads a tbdrsim results database through v_run_summary and v_dram_class (finished runs). The
selection must hold one configuration (pick it with --config) and one scene and frame size; runs
of one technique from different traces are separate bars; only repetitions are averaged.

    tbdrsim plot dram --db study/study.db --out dram.png
    /usr/bin/python3 analysis/plot_dram.py --db out/sweep.db --config series6xt_gx6450 --lights 1024
"""
import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

#: Inches kept free at the right for the legend of traffic classes (their longest name).
LEGEND_WIDTH = 2.3


def draw(args, db, runs):
    """The plot of the selected `runs` of `db`, for plot_dram.py and plot_techniques.py --metric
    dram_classes."""
    panels, fixed = pc.facets(runs, facet=("lights",))
    ids = pc.int_list(runs.run_id)
    d = pc.query(db, "SELECT run_id, class, total_mb, requested_total_mb FROM v_dram_class WHERE run_id IN (%s)" % ids)
    if d.empty:
        pc.fail("--db %s: the selected runs recorded no DRAM traffic per class" % args.db)
    d = d.merge(runs, on="run_id")
    per_run = d.groupby("run_id")[["total_mb", "requested_total_mb"]].sum(min_count=1).reset_index()
    if d.total_mb.isna().all():
        pc.fail("--db %s: the selected runs have no DRAM device figures (written before the memory system model)"
                % args.db)
    classes = pc.ordered(d[d.total_mb > 0]["class"].unique(), pc.DRAM_CLASSES)
    n = len(panels)
    width = max(6.0, 0.55 * runs.series.nunique() + 3.5)
    fig, axes = plt.subplots(n, 1, figsize=(width + LEGEND_WIDTH, 4.8 * n), squeeze=False)
    for ax, (ptitle, pr) in zip(axes[:, 0], panels):
        p = d[d.run_id.isin(pr.run_id)]
        table = p.groupby(["series", "class"]).total_mb.mean().unstack(fill_value=0.0)
        table = table.reindex(columns=classes, fill_value=0.0)
        table = table.loc[table.sum(axis=1).sort_values().index]
        x = list(range(len(table)))
        pc.stacked_bars(ax, table, pc.CLASS_COLORS)
        req = per_run.merge(pr, on="run_id").groupby("series").requested_total_mb.mean().reindex(table.index)
        if req.notna().any():
            ax.scatter(x, req, marker="_", s=300, color="black", zorder=3, label="requested (before the caches)")
        ax.set_ylabel("DRAM traffic at the devices (MB, read + written)")
        if ptitle:
            ax.set_title(ptitle, fontsize=9)
    pc.share_y(axes[:, 0], args)
    note = pc.repetition_note(runs)
    fig.suptitle("DRAM traffic by class at the devices (tick: requested before the caches)\n%s%s"
                 % (pc.title_line(fixed), "\n(" + note + ")" if note else ""), fontsize=10)
    pc.side_legend(fig, axes[0, 0], "traffic class", LEGEND_WIDTH)
    pc.save(fig, args.out, "%d runs, %d series, %d panel(s)" % (len(runs), runs.series.nunique(), n))


def main():
    draw(*pc.open_selection(__doc__, "dram.png"))


if __name__ == "__main__":
    pc.run(main)
