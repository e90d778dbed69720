#!/usr/bin/python3
"""Energy by component: one bar per technique (and variant), the frame's energy in mJ stacked by
component (DRAM, caches, tile buffer, tag and depth buffer, ROP caches, ALU, texture, static), a panel per
configuration and light count in the selection.

Reads a tbdrsim results database through v_run_summary and v_energy_component (finished runs).
Different scenes or frame sizes are refused (pick one with --scene / --where); runs of one
technique from different traces are separate bars; only repetitions are averaged.

    tbdrsim plot energy --db study/study.db --out energy.png
    /usr/bin/python3 analysis/plot_energy.py --db out/sweep.db --config series6xt_gx6450 --lights 256
"""
import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

#: Inches kept free at the right for the legend of components (their longest name).
LEGEND_WIDTH = 2.4


def main():
    args, db, runs = pc.open_selection(__doc__, "energy.png", pc.flag(
        "--share", "each bar as percentages of its total (bars stay in the order of their mJ)"))
    panels, fixed = pc.facets(runs, facet=("config", "lights"))
    ids = pc.int_list(runs.run_id)
    d = pc.query(db, "SELECT run_id, component, energy_mj FROM v_energy_component WHERE run_id IN (%s)" % ids)
    if d.empty:
        pc.fail("--db %s: the selected runs recorded no energy (runs written before the energy model)" % args.db)
    d = d.merge(runs, on="run_id")
    components = pc.ordered(d.component.unique(), pc.ENERGY_COMPONENTS)
    n = len(panels)
    fig, axes = pc.bar_panels(panels, runs, 4.8, LEGEND_WIDTH)
    for ax, (ptitle, pr) in zip(axes.flat, panels):
        p = d[d.run_id.isin(pr.run_id)]
        table = p.groupby(["series", "component"]).energy_mj.mean().unstack(fill_value=0.0)
        table = table.reindex(columns=components, fill_value=0.0)
        table = table.loc[table.sum(axis=1).sort_values().index]
        if args.share:
            table = table.div(table.sum(axis=1), axis=0) * 100.0
        pc.stacked_bars(ax, table, pc.ENERGY_COLORS, totals=not args.share)
        ax.set_ylabel("share of the frame's energy (%)" if args.share else "energy per frame (mJ)")
        if ptitle:
            ax.set_title(ptitle, fontsize=9)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    pc.share_y(axes.flat, args)
    note = pc.repetition_note(runs)
    fig.suptitle("Energy per frame by component\n%s%s" % (pc.title_line(fixed), "\n(" + note + ")" if note else ""),
                 fontsize=10)
    pc.side_legend(fig, axes[0, 0], "component", LEGEND_WIDTH)
    pc.save(fig, args.out, "%d runs, %d series, %d panel(s)" % (len(runs), runs.series.nunique(), n))


if __name__ == "__main__":
    pc.run(main)
