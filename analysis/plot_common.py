"""What the plot scripts share: their common options, the read-only results database, the run
selection (--where, --config, --lights) and one marker and colour per technique."""
import sqlite3

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = "os^vD<>pP*Xhd"


def add_common_args(ap, out, metric, metric_help, where_help="SQL condition on v_run_summary's columns"):
    """--db, --out (default `out`), --metric (default `metric`) and --where."""
    ap.add_argument("--db", required=True, help="results database")
    ap.add_argument("--out", default=out, help="PNG to write (default: %s)" % out)
    ap.add_argument("--metric", default=metric, help=metric_help)
    ap.add_argument("--where", help=where_help)


def add_selection_args(ap, lights=False):
    """--config, and --lights when the plot does not put the light count on an axis."""
    ap.add_argument("--config", help="only runs of this config_name")
    if lights:
        ap.add_argument("--lights", type=int, help="only runs with this light count")


def connect(path):
    """The results database, read-only."""
    return sqlite3.connect("file:%s?mode=ro" % path, uri=True)


def selection(args, table=""):
    """SQL condition on v_run_summary (aliased `table`, when given) selecting finished runs by
    --where, --config and --lights, and the list of captions describing it."""
    col = table + "." if table else ""
    conds, caption = [col + "status = 'ok'"], []
    if args.where:
        conds.append("(" + args.where + ")")
        caption.append(args.where)
    if getattr(args, "config", None):
        conds.append(col + "config_name = '" + args.config.replace("'", "''") + "'")
        caption.append("config " + args.config)
    if getattr(args, "lights", None) is not None:
        conds.append(col + "lights = %d" % args.lights)
        caption.append("%d lights" % args.lights)
    return " AND ".join(conds), caption


def technique_style(i):
    """The marker and colour of the i-th technique, the same in every panel and plot."""
    return {"marker": MARKERS[i % len(MARKERS)], "color": plt.cm.tab20(i % 20)}
