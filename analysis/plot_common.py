"""What every plot script shares (docs/plots.md):

- the one palette: each technique, DRAM traffic class, energy component, timed unit and pass phase
  always gets the same colour (and each technique the same marker), in every plot;
- the command line: common options, one-line errors (exit 2, never a traceback) on bad input;
- the results database, opened read-only, read through the views of analysis/views.sql;
- the run selection (--config, --lights, --technique, --scene, --where) and what it may mix: the
  dimensions a plot does not show on an axis (configuration, scene, frame size, light count) are
  either one value (named in the title), a panel each (facets), or refused with a message; runs of
  one technique from different traces (technique options, seeds, viewpoints) are separate series,
  never averaged; only repetitions of the same (configuration, trace) are averaged;
- titles naming the configuration, scene, frame and light count; readable log-scale ticks.
"""
import argparse
import math
import os
import re
import sqlite3
import sys
import urllib.parse
import zlib

#: The name messages start with: the script's, or `tbdrsim plot KIND` when that command runs it.
PROG = os.environ.get("TBDRSIM_PLOT_PROG") or os.path.splitext(os.path.basename(sys.argv[0] or "plot"))[0]

try:
    import matplotlib

    matplotlib.use("Agg")  # file output only: no display needed
    import matplotlib.pyplot as plt  # noqa: E402
    import matplotlib.ticker as mticker  # noqa: E402
    import pandas as pd  # noqa: E402
except ImportError as e:  # pragma: no cover - depends on the interpreter
    sys.stderr.write("%s: error: %s lacks the module '%s' (Debian: apt-get install python3-matplotlib "
                     "python3-pandas, or scripts/install_deps.sh; run the scripts with /usr/bin/python3)\n"
                     % (PROG, sys.executable, e.name))
    sys.exit(2)

# ---------------------------------------------------------------------------------------------
# The palette. Names the simulator writes (sim: workloads/techniques/, models/frame_address_map.cpp
# DramClass, models/energy.cpp terms, models/timing_model.cpp unit names); a name not listed gets a
# colour from its CRC-32, so it too is the same in every plot.

#: tab20 and tab20b colours, spaced so that neighbours in the lists below differ.
_TAB = [plt.cm.tab20(i) for i in range(20)] + [plt.cm.tab20b(i) for i in range(20)]

#: The 13 many-light techniques (`tbdrsim trace --list`), in `trace --list` order.
TECHNIQUES = ["plain_forward", "forward_multipass", "deferred", "light_prepass", "tiled_deferred", "forward_plus",
              "clustered_forward", "clustered_deferred", "practical_clustered_forward",
              "cascaded_clustered_forward", "deferred_tile_store", "forward_light_stack", "visibility_buffer"]
TECHNIQUE_COLORS = dict(zip(TECHNIQUES, [_TAB[i] for i in (0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 21, 25, 33)]))
TECHNIQUE_MARKERS = dict(zip(TECHNIQUES, "os^vD<>pP*Xhd"))

#: DRAM traffic classes, in the simulator's order (DramClass).
DRAM_CLASSES = ["parameter_buffer", "vertices", "indices", "textures", "color", "depth_stencil", "gbuffer",
                "visibility", "light_data", "light_lists", "work_lists", "spill", "other"]
CLASS_COLORS = dict(zip(DRAM_CLASSES, [_TAB[i] for i in (0, 1, 15, 4, 6, 2, 8, 9, 10, 11, 16, 3, 14)]))

#: Energy components (models/energy.cpp), in its order.
ENERGY_COMPONENTS = ["dram", "caches", "tile_buffer", "tag_and_depth_buffer", "rop_caches", "alu", "texture",
                     "static"]
ENERGY_COLORS = dict(zip(ENERGY_COMPONENTS, [_TAB[i] for i in (6, 2, 4, 8, 12, 0, 10, 15)]))

#: Timed units (models/timing_model.cpp), in pipeline order.
UNITS = ["binning", "tile_fetch", "isp", "usc", "texture", "tile_buffer", "pixel_back_end"]
UNIT_COLORS = dict(zip(UNITS, [_TAB[i] for i in (0, 18, 2, 4, 10, 8, 6)]))

#: Phases of a command on the timeline: a render pass's binning (geometry) and its tile work, a
#: compute dispatch.
PHASE_COLORS = {"binning": _TAB[1], "tiles": _TAB[0], "compute": _TAB[4]}

#: Line styles that tell variants (technique options, traces) of one technique apart.
VARIANT_STYLES = ["-", "--", ":", "-."]


def _hashed(name):
    return _TAB[zlib.crc32(name.encode()) % len(_TAB)]


def color(palette, name):
    """The colour of `name` in `palette` (TECHNIQUE_COLORS, CLASS_COLORS, ...); stable for unknown names."""
    return palette.get(name) or _hashed(name)


def technique_style(technique, variant_index=0):
    """Colour, marker and line style of a technique's series: the same in every panel and plot."""
    return {"color": color(TECHNIQUE_COLORS, technique),
            "marker": TECHNIQUE_MARKERS.get(technique, "o"),
            "linestyle": VARIANT_STYLES[variant_index % len(VARIANT_STYLES)]}


def ordered(names, order):
    """`names` in the simulator's `order`, names it does not list after them, sorted."""
    names = list(dict.fromkeys(names))
    return [n for n in order if n in names] + sorted(n for n in names if n not in order)


# ---------------------------------------------------------------------------------------------
# Errors and the command line.

class PlotError(Exception):
    """Bad input (a missing database, an unknown option value, a selection without runs): one line,
    exit 2."""


def fail(message):
    raise PlotError(message)


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors: 'plot_x: error: ... (see --help)', exit 2."""

    def error(self, message):
        sys.stderr.write("%s: error: %s (see --help)\n" % (self.prog, message))
        sys.exit(2)


def parser(doc, out):
    """The parser of a plot script with the options every plot takes: --db, --out, the selection."""
    ap = ArgumentParser(prog=PROG, description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--db", required=True, help="results database (tbdrsim run / sweep / study)")
    ap.add_argument("--out", default=out, help="PNG to write (default: %s)" % out)
    ap.add_argument("--where", help="SQL condition on v_run_summary's columns, e.g. \"lights = 256\"")
    ap.add_argument("--config", action="append",
                    help="only runs of this configuration: its label, as the messages list them, or a preset's name "
                         "(every configuration of it); repeatable")
    ap.add_argument("--lights", type=int, action="append", help="only runs with this light count; repeatable")
    ap.add_argument("--technique", action="append", help="only this technique; repeatable")
    ap.add_argument("--scene", help="only runs of this scene (v_run_summary.scene)")
    ap.add_argument("--fix", action="append", default=[], metavar="KEY=VALUE",
                    help="only runs with this parameter value: a hardware parameter (`tbdrsim params`), a technique "
                         "option (technique.pls_bytes) or a trace key (trace.camera), as report --by takes; repeatable")
    ap.add_argument("--independent-y", action="store_true",
                    help="each panel its own y scale (default: the panels of a figure share one, so that they compare)")
    return ap


def run(main):
    """Runs a script's main(): bad input is one line on stderr and exit 2; an unexpected failure is
    one line and exit 1 (TBDRSIM_PLOT_DEBUG=1 shows the traceback)."""
    try:
        main()
    except PlotError as e:
        sys.stderr.write("%s: error: %s\n" % (PROG, e))
        sys.exit(2)
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as e:  # noqa: BLE001 - anything else is a bug of the script
        if os.environ.get("TBDRSIM_PLOT_DEBUG"):
            raise
        sys.stderr.write("%s: internal error: %s: %s (TBDRSIM_PLOT_DEBUG=1 shows where)\n"
                         % (PROG, type(e).__name__, e))
        sys.exit(1)


# ---------------------------------------------------------------------------------------------
# The database.

#: The application id tbdrsim stamps on its databases ("TBDR"; analysis/results_db.hpp).
TBDRSIM_APPLICATION_ID = 0x54424452
_VIEWS_SQL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "views.sql")


def _temp_views(db):
    """Creates this checkout's views (views.sql beside the scripts) as TEMP views, which shadow the
    database's own without writing to it; False when they do not fit the database's schema (then
    the database's own views are used)."""
    try:
        with open(_VIEWS_SQL, encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return False
    lines = [ln for ln in text.splitlines() if not ln.startswith("DROP VIEW")]
    sql = "\n".join(lines).replace("CREATE VIEW ", "CREATE TEMP VIEW ")
    try:
        db.executescript(sql)
        return True
    except sqlite3.Error:
        for (name,) in db.execute("SELECT name FROM sqlite_temp_master WHERE type = 'view'").fetchall():
            db.execute("DROP VIEW temp.%s" % name)
        return False


class Database(sqlite3.Connection):
    """A read-only connection to a results database that knows its file (`path`, for messages)."""

    path = ""


def connect(path):
    """The results database at `path`, read-only, with the analysis views; PlotError naming the
    file when it is absent or not a tbdrsim database."""
    if not os.path.exists(path):
        fail("--db %s: no such results database" % path)
    if not os.path.isfile(path):
        fail("--db %s: not a results database file (a folder or a device)" % path)
    uri = "file:%s?mode=ro" % urllib.parse.quote(os.path.abspath(path))
    try:
        db = sqlite3.connect(uri, uri=True, factory=Database)
        app_id = db.execute("PRAGMA application_id").fetchone()[0]
    except sqlite3.Error as e:
        fail("--db %s: not a SQLite database (%s)" % (path, e))
    if app_id != TBDRSIM_APPLICATION_ID:
        fail("--db %s: not a tbdrsim results database" % path)
    if not _temp_views(db):
        have = db.execute("SELECT count(*) FROM sqlite_master WHERE type = 'view' AND name = 'v_run_summary'")
        if have.fetchone()[0] == 0:
            fail("--db %s: has no analysis views; open it once with tbdrsim (tbdrsim report --db %s)" % (path, path))
    db.path = path
    return db


def query(db, sql, params=(), where=None):
    """A DataFrame of `sql`; PlotError naming --where (when given) or the database on an SQL error."""
    try:
        return pd.read_sql_query(sql, db, params=params)
    except (sqlite3.Error, pd.errors.DatabaseError) as e:
        msg = str(e).split(": ", 1)[-1] if "Execution failed" in str(e) else str(e)
        if where:
            fail("--where \"%s\": %s" % (where, msg))
        fail("--db %s: %s (a database from another tbdrsim version? tbdrsim report --db %s migrates it)"
             % (db.path, msg, db.path))


def has_column(db, view, column):
    """Whether `view` (or table) has `column` (views grow with tbdrsim versions)."""
    return any(r[1] == column for r in db.execute("PRAGMA table_info(%s)" % view).fetchall())


# ---------------------------------------------------------------------------------------------
# The selection and its dimensions.

#: The dimensions a plot may mix only by showing them: (column, what the messages call it, the
#: option that picks one value).
DIMENSIONS = [("config", "configurations", "--config NAME"), ("scene", "scenes", "--scene NAME"),
              ("frame", "frame sizes", "--where \"width = W\""), ("lights", "light counts", "--lights N")]


def int_list(values):
    """'3,4,7': whole numbers (run ids, light counts) for an SQL `IN (...)`."""
    return ",".join(str(int(i)) for i in values)


def _sql_list(values):
    return ",".join("'" + str(v).replace("'", "''") + "'" for v in values)


def load_runs(db, args):
    """The finished runs of the selection (--where, --config, --lights, --technique, --scene,
    --fix), one row each: run_id, technique, variant, series, scene,
    config (label), config_hash, trace_hash, trace_path, frame, lights. PlotError when none."""
    folder = os.path.dirname(os.path.abspath(args.out))
    if not os.path.isdir(folder):  # before any work
        fail("--out %s: no such folder %s" % (args.out, folder))
    label = "config_label" if has_column(db, "v_run_summary", "config_label") else "config_name"
    conds = []
    if args.where:
        conds.append("(" + args.where + ")")
    if getattr(args, "technique", None):
        conds.append("technique IN (%s)" % _sql_list(args.technique))
    if getattr(args, "scene", None):
        conds.append("scene = " + _sql_list([args.scene]))
    lights = "lights IN (%s)" % int_list(args.lights) if getattr(args, "lights", None) else None
    unfinished = _unfinished(db, args, label, conds, lights)
    conds = ["status = 'ok'"] + conds + ([lights] if lights else [])
    runs = query(db, "SELECT run_id, technique, scene, config_name, %s AS config_label, config_hash, trace_hash, "
                     "trace_path, width, height, samples_per_pixel, lights FROM v_run_summary WHERE %s ORDER BY run_id"
                 % (label, " AND ".join(conds)), where=args.where)
    if runs.empty:
        total, ok = db.execute("SELECT count(*), sum(status = 'ok') FROM runs").fetchone()
        if not total:
            fail("--db %s: the database holds no runs" % db.path)
        if not ok:
            fail("--db %s: none of its %d runs finished (SELECT error FROM runs)" % (db.path, total))
        have = query(db, "SELECT group_concat(DISTINCT technique) AS t, group_concat(DISTINCT %s) AS c, "
                         "group_concat(DISTINCT CAST(lights AS INTEGER)) AS l FROM v_run_summary WHERE status = 'ok'"
                     % label)
        fail("no finished run matches the selection (%s); the database has techniques %s, configurations %s, "
             "light counts %s" % (describe_selection(args), have.t[0], have.c[0].replace(",", "; "), have.l[0]))
    runs["lights"] = runs.lights.round().astype("Int64")
    runs["frame"] = ["%dx%d%s" % (w, h, " %dx MSAA" % s if s and s > 1 else "")
                     for w, h, s in zip(runs.width, runs.height, runs.samples_per_pixel)]
    runs["config"] = _config_labels(db, runs, label)
    if getattr(args, "config", None):
        chosen = runs[config_matches(runs, args.config)]
        if chosen.empty:
            fail("--config %s: no selected run has this configuration; they have: %s"
                 % (", ".join(args.config), "; ".join(sorted(runs.config.unique()))))
        runs = chosen.reset_index(drop=True)
    if getattr(args, "fix", None):
        keys = [f.partition("=")[0] for f in args.fix]
        wide, num = hardware_params(db, runs, keys)
        runs = apply_fix(runs, wide, num, args.fix).reset_index(drop=True)
        if not unfinished.empty:  # failed runs store their parameters too
            wide, num = hardware_params(db, unfinished, keys)
            unfinished = apply_fix(unfinished, wide, num, args.fix, quiet=True)
    _note_unfinished(unfinished)
    runs["variant"] = _variants(db, runs)
    runs["series"] = [t + (" " + v if v else "") for t, v in zip(runs.technique, runs.variant)]
    return runs


def config_matches(runs, names):
    """Which `runs` --config `names` picks: each name is a configuration label (the `config` column,
    which the messages list) or, when no label is that name, a config_name (every configuration of
    that preset)."""
    pick = pd.Series(False, index=runs.index)
    for name in names:
        by_label = runs.config == name
        pick |= by_label if by_label.any() else runs.config_name == name
    return pick


#: Notes on what a figure leaves out (unfinished runs, runs without a partner, ...): save() puts
#: them under the figure's title and prints them.
_NOTES = []


def note(text):
    """Records that the figure leaves something out: `text` goes under the title and to stdout."""
    if text and text not in _NOTES:
        _NOTES.append(text)


#: At most this many characters of a failed run's error in the note that counts it.
ERROR_CHARS = 110


def _unfinished(db, args, label, conds, lights):
    """The runs of the selection that did not finish (failed, refused, still running): run_id,
    technique, config_name, config, status, error. A failed run has no figures, so a --lights or
    --where condition on its figures is unknown (NULL): it is counted unless a condition is false."""
    none = pd.DataFrame(columns=["run_id", "technique", "config_name", "config", "status", "error", "lights"])
    if not has_column(db, "v_run_summary", "status"):
        return none
    where = ["status <> 'ok'"] + ["(%s) IS NOT 0" % c for c in conds]
    try:
        bad = pd.read_sql_query("SELECT run_id, technique, config_name, %s AS config, status, error, lights "
                                "FROM v_run_summary WHERE %s" % (label, " AND ".join(where)), db)
    except (sqlite3.Error, pd.errors.DatabaseError):
        return none  # the selection's own query names the error
    if getattr(args, "config", None) and not bad.empty:
        bad = bad[config_matches(bad, args.config)]
    if lights and not bad.empty:
        bad = bad[bad.lights.isna() | bad.lights.round().isin(args.lights)]
    return bad.reset_index(drop=True)


#: The file:line an error message starts with (a trace's line): left out of the reasons, which
#: group runs by what went wrong.
_WHERE_PREFIX = re.compile(r"^\S+:\d+: ")


def _note_unfinished(bad):
    """Notes the runs that did not finish, per status and reason, with their techniques: plots
    draw finished runs only."""
    if bad.empty:
        return
    reason = bad.error.fillna("").str.split("\n").str[0].map(lambda e: _WHERE_PREFIX.sub("", e))
    reasons = []
    for (status, error), g in bad.groupby([bad.status, reason]):
        why = error if len(error) <= ERROR_CHARS else error[:ERROR_CHARS - 3] + "..."
        reasons.append("%d %s (%s)%s" % (len(g), status, ", ".join(ordered(g.technique.unique(), TECHNIQUES)),
                                         ": " + why if why else ""))
    note("left out: %d run(s) that did not finish: %s" % (len(bad), "; ".join(reasons)))


def option(*names, **kwargs):
    """One option a script adds to the common ones, for open_selection(): argparse's
    add_argument(*names, **kwargs)."""
    return names, kwargs


def flag(name, help):
    """An on/off option (store_true), for open_selection()."""
    return option(name, action="store_true", help=help)


def metric_option(default, examples):
    """--metric: the v_metric figure a script draws, `examples` naming a few others."""
    return option("--metric", default=default, help="a v_metric name (default %s; %s)" % (default, examples))


def open_selection(doc, out, *options):
    """Parses the command line (parser()'s options and the script's `options`), opens --db and
    loads the selected runs: (args, db, runs)."""
    ap = parser(doc, out)
    for names, kwargs in options:
        ap.add_argument(*names, **kwargs)
    args = ap.parse_args()
    db = connect(args.db)
    return args, db, load_runs(db, args)


def first_per_series(runs, descending=False):
    """The first run of each series (a run's timeline or tile map is not an average), in the
    techniques' order (descending: the reverse, for a chart drawn bottom-up), then by series."""
    first = runs.sort_values("run_id").drop_duplicates("series")
    first = first.assign(order=[ordered(first.technique, TECHNIQUES).index(t) for t in first.technique])
    return first.sort_values(["order", "series"], ascending=not descending).reset_index(drop=True)


def _config_labels(db, runs, label):
    """Each run's configuration label: the views' config_label when the database has it; else the
    config name followed by the parameters whose values differ between the selected configurations."""
    if label == "config_label" or runs.config_hash.nunique() == 1:
        return runs.config_label
    one = runs.drop_duplicates("config_hash")
    p = query(db, "SELECT run_id, key, value FROM run_params WHERE run_id IN (%s)"
              % int_list(one.run_id))
    wide = p.pivot(index="run_id", columns="key", values="value")
    differ = [k for k in wide.columns if wide[k].nunique(dropna=False) > 1]
    by_hash = {}
    for rid, h, name in zip(one.run_id, one.config_hash, one.config_name):
        extra = " ".join("%s=%s" % (k, wide.at[rid, k]) for k in differ if rid in wide.index)
        by_hash[h] = name + (" " + extra if extra else "")
    return runs.config_hash.map(by_hash)


def _variants(db, runs):
    """What tells apart runs of one technique at the same configuration, scene, frame and light
    count: the technique options that differ (technique.<option> parameters, when the database
    stores them), else the trace file's name; '' when the runs share their trace."""
    opts = query(db, "SELECT run_id, key, value FROM v_param WHERE key GLOB 'technique.*' AND run_id IN (%s)"
                 % int_list(runs.run_id))
    variant = pd.Series([""] * len(runs), index=runs.index)
    if not opts.empty:
        wide = opts.pivot(index="run_id", columns="key", values="value")
        for tech, g in runs.groupby("technique"):
            w = wide.reindex(g.run_id)
            differ = [k for k in w.columns if w[k].nunique(dropna=True) > 1]
            for idx, rid in zip(g.index, g.run_id):
                variant[idx] = " ".join("%s=%s" % (k[len("technique."):], w.at[rid, k]) for k in differ)
    key = ["technique", "variant", "config_hash", "scene", "frame", "lights"]
    tmp = runs.assign(variant=variant)
    for _, g in tmp.groupby(key, dropna=False):
        if g.trace_hash.nunique() > 1:  # different traces the options do not explain: name the files
            names = g.trace_path.map(lambda p: os.path.splitext(os.path.basename(p))[0])
            if names.nunique() < g.trace_hash.nunique():
                names = g.trace_path
            for idx in g.index:
                variant[idx] = (variant[idx] + " " if variant[idx] else "") + "[" + names[idx] + "]"
    return variant


def natural(value):
    """Sort key that orders numbers inside text numerically ('bits=64' before 'bits=128')."""
    parts = value if isinstance(value, tuple) else (value,)
    return [[int(t) if t.isdigit() else t for t in re.split(r"(\d+)", str(p))] for p in parts]


def describe_selection(args):
    """The selection options given, as text."""
    parts = []
    for opt in ("config", "lights", "technique", "fix"):
        v = getattr(args, opt, None)
        if v:
            parts.append("--%s %s" % (opt, ",".join(str(x) for x in v)))
    if getattr(args, "scene", None):
        parts.append("--scene " + args.scene)
    if args.where:
        parts.append("--where \"%s\"" % args.where)
    return ", ".join(parts) or "all runs"


def _dim_value_text(dim, v):
    return "%d lights" % v if dim == "lights" else ("config " + str(v) if dim == "config" else str(v))


def facets(runs, shown=(), facet=(), max_panels=8):
    """Splits the selection into panels. Dimensions in `shown` are on an axis of the plot; those in
    `facet` that vary get a panel per combination; any other that varies is refused (PlotError
    naming the values and the option that picks one). Returns [(panel title, runs)] and the list
    of (dimension, value) the whole figure shares, for its title."""
    fixed, split = [], []
    for dim, plural, option in DIMENSIONS:
        values = sorted(runs[dim].dropna().unique(), key=lambda v: (str(type(v)), v))
        if dim in shown:
            continue
        if len(values) <= 1:
            fixed.append((dim, values[0] if values else None))
        elif dim in facet:
            split.append(dim)
        else:
            fail("the selection mixes %d %s (%s) and this plot would average them; pick one with %s, "
                 "or --where" % (len(values), plural, ", ".join(str(v) for v in values), option))
    if not split:
        return [("", runs)], fixed
    short = {}
    if "config" in split:
        # Panels name what differs between the configurations; what they share goes to the title.
        labels = list(runs.config.dropna().unique())
        common = [t for t in labels[0].split(" ") if all(t in lb.split(" ") for lb in labels)]
        short = {lb: " ".join(t for t in lb.split(" ") if t not in common) or "the title's configuration" for lb in labels}
        fixed.append(("config", " ".join(common) + " (+ per panel)"))
    panels = [(", ".join(short.get(v, v) if d == "config" else _dim_value_text(d, v)
                         for d, v in zip(split, key if isinstance(key, tuple) else (key,))), g)
              for key, g in sorted(runs.groupby(split if len(split) > 1 else split[0]), key=lambda kg: natural(kg[0]))]
    if len(panels) > max_panels:
        fail("the selection has %d combinations of %s (at most %d panels); narrow it with --config, --lights "
             "or --where" % (len(panels), " and ".join(split), max_panels))
    return panels, fixed


def common_config(runs):
    """The configuration the runs share, for a title: their label when they have one, else what
    all their labels share followed by '(+ per panel)'."""
    labels = list(runs.config.dropna().unique())
    if len(labels) <= 1:
        return labels[0] if labels else None
    common = [t for t in labels[0].split(" ") if all(t in lb.split(" ") for lb in labels)]
    return " ".join(common) + " (+ per panel)"


def title_line(fixed, extra=()):
    """'config X · scene atrium:2 · 1920x1080 · 256 lights': what the figure's runs share."""
    parts = []
    for dim, v in fixed:
        if v is None:
            continue
        parts.append("%d lights" % v if dim == "lights" else ("scene " + v if dim == "scene"
                                                              else ("config " + v if dim == "config" else v)))
    return " · ".join(list(parts) + list(extra))


def repetition_note(runs):
    """'mean of 3 repetitions' when some plotted point averages repeated runs of one (config,
    trace), else ''."""
    n = runs.groupby(["config_hash", "trace_hash"]).size()
    return "" if n.max() <= 1 else "points: mean of up to %d repetitions" % n.max()


def metric_values(db, runs, metric, where=None):
    """The figure `metric` (a v_metric name) of the runs: DataFrame run_id, value, unit; PlotError
    naming the metric (with close names) when no selected run has it."""
    ids = int_list(runs.run_id)
    d = query(db, "SELECT run_id, value, unit FROM v_metric WHERE metric = ? AND run_id IN (%s)" % ids,
              params=(metric,)).dropna(subset=["value"])
    if d.empty:
        names = [r[0] for r in db.execute("SELECT DISTINCT metric FROM v_metric WHERE run_id IN (%s)" % ids)]
        import difflib
        close = difflib.get_close_matches(metric, names, n=3, cutoff=0.6)
        fail("--metric %s: no selected run has this figure%s (tbdrsim report --db %s lists the metrics)"
             % (metric, "; did you mean " + " or ".join(close) + "?" if close else "", db.path))
    return d


def average(runs, values, keys):
    """Mean of `values` (run_id, value) per `keys` of `runs`. Only repetitions share keys once
    facets() and the series (technique + variant) have split everything else."""
    return values.merge(runs, on="run_id").groupby(keys, dropna=False).value.mean().reset_index()


# ---------------------------------------------------------------------------------------------
# Axes.

#: Plain-number tick labels: 1024 not 1.02e+03 or 2^10, 0.05 not 5x10^-2.
PLAIN = mticker.FuncFormatter(lambda v, _: "%d" % round(v) if v >= 1 and abs(v - round(v)) < 1e-9
                              else "%g" % float("%.3g" % v))


def log_ticks(target, lo, hi, fixed=None):
    """Readable ticks on a log-scaled matplotlib Axis `target`: at `fixed` values when given, else
    at 1, 2, 5 x 10^k (1 x 10^k beyond three decades), with plain-number labels."""
    if fixed is not None:
        target.set_major_locator(mticker.FixedLocator(fixed))
    else:
        decades = math.log10(hi / lo) if lo > 0 else 99
        target.set_major_locator(mticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0) if decades < 3 else (1.0,)))
    target.set_major_formatter(PLAIN)
    target.set_minor_formatter(mticker.NullFormatter())


def log_axis(ax, axis, values, base=10):
    """A log scale on `axis` ('x' or 'y') with readable ticks (log_ticks): on the values themselves
    for a base-2 axis or a few x values, else at 1, 2, 5 x 10^k."""
    vals = sorted(v for v in values if v > 0 and math.isfinite(v))
    (ax.set_xscale if axis == "x" else ax.set_yscale)("log", base=base)
    target = ax.xaxis if axis == "x" else ax.yaxis
    few = base == 2 or (len(set(vals)) <= 8 and axis == "x")
    log_ticks(target, vals[0], vals[-1], sorted(set(vals)) if few else None)


def wide_range(values, factor):
    """Whether positive `values` span more than `factor` (then a log axis reads better)."""
    v = [x for x in values if x > 0]
    return len(v) == len(list(values)) and len(v) > 1 and max(v) > factor * min(v)


#: How the panels' y scales were set (share_y), for save()'s line: "one y scale" or "y scale per panel".
_Y_SCALE = []


def share_y(axes, args):
    """Gives the panels `axes` one y scale (the union of their ranges) unless --independent-y:
    panels of one figure compare at a glance. Call after drawing, before any log_axis."""
    axes = [ax for ax in axes if ax.get_visible()]
    if len(axes) < 2:
        return
    if getattr(args, "independent_y", False):
        _Y_SCALE[:] = ["y scale per panel"]
        return
    _Y_SCALE[:] = ["one y scale"]
    first = axes[0]
    for ax in axes[1:]:
        ax.sharey(first)
    first.autoscale_view(scalex=False)  # over the data of every panel that shares the axis


#: Values spanning more than this factor get a log axis by default: beyond ~20x the small values
#: of a linear axis are flat against zero.
LOG_RANGE = 20.0


#: Characters of a title line per inch of figure width (10-point text) when notes are wrapped.
TITLE_CHARS_PER_INCH = 13


def _fit_below_title(fig):
    """Moves the panels down until nothing of them (titles, tick labels) reaches into the figure's
    title or into a text placed above them, measured as drawn."""
    renderer = fig.canvas.get_renderer()
    texts = [fig._suptitle] + [t for t in fig.texts if t.get_visible()]
    for _ in range(3):
        fig.canvas.draw()
        bottom = min(t.get_window_extent(renderer).y0 for t in texts)
        top = max((ax.get_tightbbox(renderer).y1 for ax in fig.axes if ax.get_visible() and getattr(ax, "get_subplotspec", lambda: None)()),
                  default=0.0)
        overlap = top - bottom + 8.0  # pixels of space between them
        if overlap <= 0:
            return
        fig.subplots_adjust(top=fig.subplotpars.top - overlap / fig.bbox.height)


def save(fig, out, summary):
    """Writes the figure to `out` (PlotError naming --out when it cannot) and prints `summary` and
    the figure's title on one line, then each note() (what the figure leaves out), which the title
    also shows."""
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        fail("--out %s: no such folder %s" % (out, folder))
    title = fig._suptitle.get_text().replace("\n", " | ") if fig._suptitle else ""
    if _NOTES:
        text = "\n".join("(" + n + ")" for n in _NOTES)
        if fig._suptitle:
            fig._suptitle.set_text(fig._suptitle.get_text() + "\n" + text)
        else:
            fig.suptitle(text, fontsize=10)
    if fig._suptitle:
        # Lines as wide as the figure at most (a long title is wrapped, never cut at its edges).
        import textwrap
        width = max(40, int(TITLE_CHARS_PER_INCH * fig.get_figwidth()))
        fig._suptitle.set_text("\n".join(textwrap.fill(line, width) for line in fig._suptitle.get_text().split("\n")))
        # Room for the title above the panels (tight_layout leaves it out): about 0.2 inch a line,
        # then as much more as the panels' own titles need (measured).
        lines = fig._suptitle.get_text().count("\n") + 1
        top = 1.0 - (0.2 * lines + 0.15) / fig.get_figheight()
        if fig.subplotpars.top > top:
            fig.subplots_adjust(top=top)
        _fit_below_title(fig)
    try:
        fig.savefig(out, dpi=120)
    except (OSError, ValueError) as e:
        fail("--out %s: %s" % (out, e))
    plt.close(fig)
    print("wrote %s (%s): %s" % (out, ", ".join([summary] + _Y_SCALE), title))
    for n in _NOTES:
        print("  " + n)


def stacked_bars(ax, table, palette, totals=True):
    """One bar per row of `table` (index: series, columns: parts in order), the parts stacked in
    their `palette` colours, each bar's total written above it (unless not `totals`); returns the
    totals."""
    x = list(range(len(table)))
    bottom = [0.0] * len(table)
    for part in table.columns:
        ax.bar(x, table[part], bottom=bottom, width=0.7, color=color(palette, part), label=part)
        bottom = [b + v for b, v in zip(bottom, table[part])]
    for i, total in zip(x, bottom if totals else []):
        ax.annotate("%.3g" % total, (i, total), ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x)
    ax.set_xticklabels(table.index, rotation=35, ha="right", fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    return bottom


#: Bar panels per row of a figure of bar panels (two keep each bar's label readable).
BAR_PANEL_COLUMNS = 2


def bar_panels(panels, runs, panel_height, legend_width=0.0):
    """A figure of one bar panel per entry of `panels`, BAR_PANEL_COLUMNS a row, each wide enough
    for one bar per series of `runs` (0.55 in a bar, 3 in of axes), with `legend_width` inches free
    at the right: (fig, axes as a 2-D array)."""
    cols = min(len(panels), BAR_PANEL_COLUMNS)
    rows = (len(panels) + cols - 1) // cols
    width = max(6.0, 0.55 * runs.series.nunique() + 3)
    return plt.subplots(rows, cols, figsize=(width * cols + legend_width, panel_height * rows), squeeze=False)


def side_legend(fig, ax, title, legend_width):
    """The legend of `ax`'s labelled artists at the figure's right, outside the panels, which
    tight_layout keeps `legend_width` inches free for."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, title=title, fontsize=8, title_fontsize=9, loc="center right")
    fig.tight_layout(rect=(0, 0, 1 - legend_width / fig.get_figwidth(), 1))


def hardware_params(db, runs, extra=()):
    """The resolved hardware parameters of the runs: (text, number) DataFrames indexed by run_id,
    a column per key (v_param without the trace.*, config.* and technique.* pseudo-keys), and the
    `extra` keys of v_param among those (technique options, trace keys: whatever report --by
    takes; a run without one has NaN)."""
    extra = sorted(set(k for k in extra if k.split(".")[0] in ("trace", "config", "technique")))
    p = query(db, "SELECT run_id, key, value, value_num FROM v_param WHERE run_id IN (%s) AND ((key NOT GLOB "
                  "'trace.*' AND key NOT GLOB 'config.*' AND key NOT GLOB 'technique.*')%s)"
              % (int_list(runs.run_id), " OR key IN (%s)" % _sql_list(extra) if extra else ""))
    return (p.pivot(index="run_id", columns="key", values="value").reindex(runs.run_id),
            p.pivot(index="run_id", columns="key", values="value_num").reindex(runs.run_id))


def apply_fix(runs, wide, num, fixes, quiet=False):
    """The runs whose parameters have the --fix KEY=VALUE values (numbers compare as numbers);
    PlotError when a fix matches none (unless `quiet`: then no runs)."""
    for fix in fixes:
        key, sep, value = fix.partition("=")
        if quiet:
            if key not in wide.columns:
                return runs.iloc[0:0]
            keep = (wide.loc[runs.run_id, key] == value) | (num.loc[runs.run_id, key] == pd.to_numeric(value, errors="coerce"))
            runs = runs[keep.values]
            continue
        if not sep or key not in wide.columns:
            fail("--fix %s: expected KEY=VALUE with a parameter key (tbdrsim params lists them), a technique option "
                 "(technique.<option>) or a trace key (trace.<key>) that the selected runs have" % fix)
        w, nm = wide.loc[runs.run_id, key], num.loc[runs.run_id, key]
        keep = (w == value) | (nm == pd.to_numeric(value, errors="coerce"))
        if not keep.any():
            fail("--fix %s: no selected run has this value (they have %s)"
                 % (fix, ", ".join(sorted(w.dropna().unique(), key=natural))))
        runs = runs[keep.values]
    return runs
