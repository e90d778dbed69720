#!/usr/bin/python3
"""Frame sequences over time: per frame of each sequence run, its interval (ms: its end less the end
of the frame before), the DRAM bytes moved in that interval (MB) and its energy (mJ), one line per
technique (and variant) of one configuration and light count; the steady frames (after the first,
before the last) are the solid part of each line (docs/sequences.md).

Reads a tbdrsim results database (the sequence/frame<k> statistics of runs of traces with more than
one frame). A sampled run (tbdrsim run --sample K) is drawn from its sampling/frame<k> rows: every
frame's figures, its representative's where it was not simulated, with a ring on each simulated
frame. The selection must hold one configuration, scene, frame size and light count; of
repetitions, the first run is drawn.

    tbdrsim plot sequence --db study/study.db --out sequence.png
    /usr/bin/python3 analysis/plot_sequence.py --db seq.db --technique forward_plus --technique deferred
"""
import plot_common as pc  # first: it selects matplotlib's file-only backend and checks the modules

plt = pc.plt

#: The per-frame figures drawn, a panel each: (statistic, scale to the axis' unit, axis label).
PANELS = (("interval_ms", 1.0, "frame interval (ms)"),
          ("dram_interval_bytes", 1e-6, "DRAM in the interval (MB, at the devices)"),
          ("energy_mj", 1.0, "energy (mJ)"))


def main():
    args, db, runs = pc.open_selection(__doc__, "sequence.png")
    _, fixed = pc.facets(runs)  # one configuration, scene, frame and light count
    first = pc.first_per_series(runs)
    ids = pc.int_list(first.run_id)
    # Both prefixes are 14 characters: the frame number starts at character 15.
    stats = pc.query(db, "SELECT run_id, substr(scope, 1, 8) AS kind, CAST(substr(scope, 15) AS INTEGER) AS frame, name, value "
                         "FROM stats WHERE run_id IN (%s) AND (scope GLOB 'sequence/frame[0-9]*' OR scope GLOB 'sampling/frame[0-9]*') "
                         "AND name IN (%s, 'representative')"
                     % (ids, ", ".join("'%s'" % p[0] for p in PANELS)))
    # A sampled run: its sampling rows (every frame), not the representatives' sequence rows.
    sampled = set(stats[stats.kind == "sampling"].run_id)
    stats = stats[(stats.kind == "sampling") | ~stats.run_id.isin(sampled)]
    if stats.empty:
        pc.fail("no run of a sequence in the selection (a trace of more than one frame: tbdrsim trace --frames N, "
                "docs/sequences.md)")
    fig, axes = plt.subplots(len(PANELS), 1, figsize=(10.0, 2.6 * len(PANELS) + 1.2), sharex=True, squeeze=False)
    drawn = 0
    for _, r in first.iterrows():
        s = stats[stats.run_id == r.run_id]
        if s.empty:
            continue
        drawn += 1
        frames = int(s.frame.max()) + 1
        style = pc.technique_style(r.technique)
        for ax, (name, scale, label) in zip(axes[:, 0], PANELS):
            v = s[s.name == name].sort_values("frame")
            x, y = v.frame.to_numpy(), v.value.to_numpy() * scale
            steady = (x >= 1) & ((x < frames - 1) | (frames <= 2))
            ax.plot(x, y, alpha=0.35, **style)
            ax.plot(x[steady], y[steady], label=r.series + (" (sampled)" if r.run_id in sampled else ""), **style)
            if r.run_id in sampled:
                rep = set(s[(s.name == "representative") & (s.value == 1)].frame)
                dots = [i for i, f in enumerate(x) if f in rep]
                ax.plot(x[dots], y[dots], linestyle="none", marker="o", markersize=9, markerfacecolor="none",
                        markeredgecolor="black", label="simulated frames" if ax is axes[0, 0] else None)
            ax.set_ylabel(label, fontsize=8)
            ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("frame")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="center right")
    fig.suptitle("Sequences, frame by frame (steady frames solid)\n%s" % pc.title_line(fixed), fontsize=10)
    fig.tight_layout(rect=(0, 0, 1 - 2.6 / fig.get_figwidth(), 1))
    pc.save(fig, args.out, "%d sequence run(s), %d frames" % (drawn, int(stats.frame.max()) + 1))


if __name__ == "__main__":
    pc.run(main)
