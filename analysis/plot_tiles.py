#!/usr/bin/python3
"""Per-tile heat maps: for each technique (and variant) of one configuration and light count, the
work of every screen tile (--value: cycles from fetch to writeback, samples, or DRAM bytes), summed
over the frame's passes or of one pass (--pass). One colour scale for all panels, so tiles compare
across techniques; the title names the configuration, scene, frame size and light count, each
panel its technique and run.

Reads a tbdrsim results database (v_run_summary, tile_stats, v_param's tiling.tile_width/height)
of finished runs. The selection must hold one configuration, scene, frame size and light count
(pick them with --config, --lights, --where); of repetitions, the first run is drawn.

    tbdrsim plot tiles --db study/study.db --lights 1024 --out tiles.png
    /usr/bin/python3 analysis/plot_tiles.py --db out/sweep.db --value dram_bytes --technique deferred --lights 256
"""
import numpy as np

import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

VALUES = {"cycles": "cycles per tile (fetch to writeback)", "samples": "samples per tile",
          "dram_bytes": "DRAM bytes per tile"}
#: Panels per row of the figure.
COLUMNS = 4
#: Inches at the right for the colour bar, its tick labels and its label.
COLORBAR_WIDTH = 1.3


def main():
    args, db, runs = pc.open_selection(
        __doc__, "tiles.png",
        pc.option("--value", default="cycles", choices=sorted(VALUES), help="what each tile shows (default cycles)"),
        pc.option("--pass", dest="pass_index", type=int, help="only this render pass (index; default: all summed)"),
        pc.flag("--log", "log colour scale"))
    _, fixed = pc.facets(runs)
    first = pc.first_per_series(runs)
    ids = pc.int_list(first.run_id)
    cond = "" if args.pass_index is None else " AND pass = %d" % args.pass_index
    t = pc.query(db, "SELECT run_id, tile_x, tile_y, sum(%s) AS v FROM tile_stats WHERE run_id IN (%s)%s "
                     "GROUP BY run_id, tile_x, tile_y" % (args.value, ids, cond))
    if t.empty:
        pc.fail("--db %s: the selected runs have no per-tile rows%s" %
                (args.db, "" if args.pass_index is None else " for --pass %d" % args.pass_index))
    wide, num = pc.hardware_params(db, first)
    tw, th = int(num["tiling.tile_width"].iloc[0]), int(num["tiling.tile_height"].iloc[0])
    w, h = int(first.width.iloc[0]), int(first.height.iloc[0])
    tx, ty = (w + tw - 1) // tw, (h + th - 1) // th
    vmax = t.v.max()
    vmin = max(t.v[t.v > 0].min(), vmax * 1e-4) if args.log and (t.v > 0).any() else 0.0
    norm = pc.matplotlib.colors.LogNorm(vmin, vmax) if args.log else pc.matplotlib.colors.Normalize(0.0, vmax)
    n = len(first)
    cols = min(COLUMNS, n)
    rows = (n + cols - 1) // cols
    aspect = h / w
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols + COLORBAR_WIDTH + 0.3, 3.6 * aspect * rows + 1.6), squeeze=False)
    im = None
    for ax, (_, r) in zip(axes.flat, first.iterrows()):
        grid = np.full((ty, tx), np.nan)
        d = t[t.run_id == r.run_id]
        grid[d.tile_y.clip(0, ty - 1), d.tile_x.clip(0, tx - 1)] = d.v
        im = ax.imshow(grid, cmap="viridis", norm=norm, extent=(0, tx * tw, ty * th, 0), interpolation="nearest")
        ax.set_title("%s (run %d)\nmean %.3g, max %.3g" % (r.series, r.run_id, np.nanmean(grid), np.nanmax(grid)),
                     fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    # The colour bar in a column of its own at the right (beside the panels, never over one).
    figw = fig.get_figwidth()
    fig.subplots_adjust(left=0.2 / figw, right=1.0 - COLORBAR_WIDTH / figw, wspace=0.08, bottom=0.3 / fig.get_figheight())
    cax = fig.add_axes([1.0 - (COLORBAR_WIDTH - 0.15) / figw, 0.12, 0.15 / figw, 0.7])
    bar = fig.colorbar(im, cax=cax, label=VALUES[args.value] +
                       ("" if args.pass_index is None else ", pass %d" % args.pass_index))
    if args.log:
        pc.log_ticks(bar.ax.yaxis, vmin, vmax)
    fig.suptitle("Per-tile %s, %dx%d-pixel tiles%s\n%s" % (
        args.value, tw, th, "" if args.pass_index is None else ", pass %d" % args.pass_index,
        pc.title_line(fixed)), fontsize=10)
    pc.save(fig, args.out, "%d heat maps, %dx%d tiles" % (n, tx, ty))


if __name__ == "__main__":
    pc.run(main)
