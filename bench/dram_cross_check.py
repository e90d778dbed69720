#!/usr/bin/env python3
"""Helpers of bench/dram_vs_dramsim3.sh and bench/dram_vs_drampower.sh (docs/dram-cross-check.md).

Subcommands (each prints key value lines, one per figure, or writes the file it is given):
  ini SRC DST section.key=value ...   a DRAMsim3 .ini with those keys set (added when absent)
  dramsim3 OUTDIR TCK_NS TRFC_CYCLES FIRST_CYCLE
                                      DRAMsim3's figures from OUTDIR/dramsim3.json and dramsim3epoch.json
  tbdrsim-db DB BURST_BYTES TRFC_NS   tbdrsim's figures of a run from its results database
  drampower5 JSON                     energies (pJ) per command class from drampower_cli --json
  drampower4 FILE...                  energies (pJ) per command class summed over drampower (4.x) outputs
  table A B [labels]                  two key value files side by side with the difference in %
"""
import json
import math
import re
import sqlite3
import sys


def kv(d):
    for k, v in d.items():
        print(f"{k} {v:.6g}" if isinstance(v, float) else f"{k} {v}")


def cmd_ini(src, dst, sets):
    lines = open(src).read().splitlines()
    for s in sets:
        key, value = s.split("=", 1)
        section, name = key.split(".", 1)
        sec_start = None
        for i, l in enumerate(lines):
            if l.strip() == f"[{section}]":
                sec_start = i
        if sec_start is None:
            lines += ["", f"[{section}]", f"{name} = {value}"]
            continue
        end = len(lines)
        for i in range(sec_start + 1, len(lines)):
            if lines[i].strip().startswith("["):
                end = i
                break
        for i in range(sec_start + 1, end):
            if re.match(rf"\s*{re.escape(name)}\s*=", lines[i]):
                lines[i] = f"{name} = {value}"
                break
        else:
            lines.insert(end, f"{name} = {value}")
    open(dst, "w").write("\n".join(lines) + "\n")


def decode_concat(text):
    """dramsim3.json: {"0": {...}, "1": {...}} (or the channels' objects one after another)."""
    text = text.strip()
    try:
        obj = json.loads(text)
        return [obj[k] for k in sorted(obj, key=int)]
    except json.JSONDecodeError:
        pass
    out, dec, i = [], json.JSONDecoder(), 0
    for m in re.finditer(r'"(\d+)"\s*:\s*', text):
        if m.start() < i:
            continue
        obj, end = dec.raw_decode(text, m.end())
        out.append(obj)
        i = end
    return out


def percentile(hist, p):
    """Nearest rank over a {value: count} histogram."""
    items = sorted((int(k), v) for k, v in hist.items())
    total = sum(v for _, v in items)
    if total == 0:
        return 0
    rank = max(1, math.ceil(p * total))
    acc = 0
    for value, count in items:
        acc += count
        if acc >= rank:
            return value
    return items[-1][0]


def cmd_dramsim3(outdir, tck_ns, trfc_cycles, first_cycle):
    tck_ns, trfc_cycles, first_cycle = float(tck_ns), float(trfc_cycles), float(first_cycle)
    chans = decode_concat(open(f"{outdir}/dramsim3.json").read())
    s = lambda k: sum(float(c.get(k, 0)) for c in chans)
    reads, writes = s("num_reads_done"), s("num_writes_done")
    hist = {}
    for c in chans:
        for k, v in c.get("read_latency", {}).items():
            hist[k] = hist.get(k, 0) + v
    n = sum(hist.values())
    mean = sum(int(k) * v for k, v in hist.items()) / n if n else 0
    # Completion: the end of the first epoch (each entry: one channel's counts over one epoch) by
    # which every transaction was done.
    done_cycle = None
    try:
        epochs = json.load(open(f"{outdir}/dramsim3epoch.json"))
        per = {}
        for e in epochs:
            per.setdefault(int(e.get("epoch_num", 0)), []).append(e)
        acc, end = 0, 0.0
        for num in sorted(per):
            end += float(per[num][0].get("num_cycles", 0))
            acc += sum(float(e.get("num_reads_done", 0)) + float(e.get("num_writes_done", 0)) for e in per[num])
            if acc >= reads + writes:
                done_cycle = end
                break
    except (OSError, json.JSONDecodeError):
        pass
    cycles = float(chans[0].get("num_cycles", 0))
    if done_cycle is None:
        done_cycle = cycles
    out = {}
    out["reads"] = reads
    out["writes"] = writes
    out["elapsed_ns"] = (done_cycle - first_cycle) * tck_ns
    out["run_cycles"] = cycles
    out["read_cmds"] = s("num_read_cmds")
    out["write_cmds"] = s("num_write_cmds")
    out["activates"] = s("num_act_cmds")
    out["precharges"] = s("num_pre_cmds")
    out["refreshes"] = s("num_ref_cmds")
    out["row_hits"] = s("num_read_row_hits") + s("num_write_row_hits")
    out["row_hit_rate_per_burst"] = 1 - out["activates"] / max(1, out["read_cmds"] + out["write_cmds"])
    out["read_latency_mean_ns"] = mean * tck_ns
    out["read_latency_p99_ns"] = percentile(hist, 0.99) * tck_ns
    # Refresh share: refreshes x tRFC over channels x the cycles simulated.
    out["refresh_share"] = out["refreshes"] * trfc_cycles / (len(chans) * cycles) if cycles else 0
    out["energy_act_pj"] = s("act_energy")
    out["energy_read_pj"] = s("read_energy")
    out["energy_write_pj"] = s("write_energy")
    out["energy_ref_pj"] = s("ref_energy") + s("refb_energy")
    bg = 0.0
    for c in chans:
        for k in ("act_stb_energy", "pre_stb_energy", "sref_energy"):
            v = c.get(k, 0)
            bg += sum(v.values()) if isinstance(v, dict) else (sum(v) if isinstance(v, list) else float(v))
    out["energy_background_pj"] = bg
    kv(out)


def cmd_tbdrsim_db(db, burst_bytes, trfc_ns):
    burst_bytes, trfc_ns = float(burst_bytes), float(trfc_ns)
    con = sqlite3.connect(db)
    rows = con.execute("select name, value from stats where scope = 'mem/dram' and run_id = (select max(run_id) from stats)")
    st = {n: v for n, v in rows}
    ft = con.execute("select value from stats where scope = 'frame/timing' and name = 'frame_time_ms' "
                     "and run_id = (select max(run_id) from stats)").fetchone()
    chans = con.execute("select count(distinct scope) from stats where scope like 'mem/dram.ch%' "
                        "and run_id = (select max(run_id) from stats)").fetchone()[0] or 1
    frame_ns = ft[0] * 1e6 if ft else 0
    bursts = (st.get("read_bytes", 0) + st.get("write_bytes", 0)) / burst_bytes
    out = {
        "reads": st.get("reads", 0), "writes": st.get("writes", 0),
        "read_bytes": st.get("read_bytes", 0), "write_bytes": st.get("write_bytes", 0),
        "achieved_bandwidth_gbps": st.get("achieved_bandwidth_gbps", 0),
        "avg_read_latency_ns": st.get("avg_read_latency_ns", 0),
        "row_hit_rate": st.get("row_hit_rate", 0),
        "row_hit_rate_per_burst": 1 - st.get("activates", 0) / bursts if bursts else 0,
        "activates": st.get("activates", 0), "precharges": st.get("precharges", 0),
        "refreshes": st.get("refreshes", 0),
        "refresh_share": st.get("refreshes", 0) * trfc_ns / (chans * frame_ns) if frame_ns else 0,
        "frame_ns": frame_ns, "channels": chans,
    }
    for k in ("energy_read_pj", "energy_write_pj", "energy_io_pj", "energy_activate_pj", "energy_background_pj",
              "energy_refresh_pj", "energy_pj"):
        out[k] = st.get(k, 0)
    kv(out)


def cmd_drampower5(path):
    j = json.load(open(path))
    core = j["CoreEnergy"]
    banks = core.get("BankEnergy") or next(v for v in core.values() if isinstance(v, list))
    tot = {}
    for b in banks:
        for k, v in b.items():
            if isinstance(v, (int, float)) and k not in ("Rank", "Device", "Bank"):
                tot[k] = tot.get(k, 0) + v
    pj = 1e12
    out = {
        "act_pre_pj": (tot.get("ACT", 0) + tot.get("PRE", 0)) * pj,
        "rd_pj": (tot.get("RD", 0) + tot.get("RDA", 0)) * pj,
        "wr_pj": (tot.get("WR", 0) + tot.get("WRA", 0)) * pj,
        "ref_pj": (tot.get("REF_AB", 0) + tot.get("REF_PB", 0) + core.get("E_refab", 0)) * pj,
        "background_pj": (tot.get("BG_ACT", 0) + tot.get("BG_PRE", 0) + core.get("E_bg_act_shared", 0) +
                          core.get("E_PDNA", 0) + core.get("E_PDNP", 0)) * pj,
    }
    out["core_total_pj"] = sum(out.values())
    iface = j.get("InterfaceEnergy", {})
    # The interface model needs impedances the memspec does not give (placeholders): reported, not compared.
    out["interface_pj"] = sum(float(v) for v in _leaves(iface)) * pj
    kv(out)


def _leaves(x):
    if isinstance(x, dict):
        for v in x.values():
            yield from _leaves(v)
    elif isinstance(x, (int, float)) and x == x:
        yield x


def cmd_drampower4(paths):
    pat = {
        "act_pj": r"ACT Cmd Energy:\s*([\d.eE+-]+)", "pre_pj": r"PRE Cmd Energy:\s*([\d.eE+-]+)",
        "rd_pj": r"RD Cmd Energy:\s*([\d.eE+-]+)", "wr_pj": r"WR Cmd Energy:\s*([\d.eE+-]+)",
        "ref_pj": r"Auto-Refresh Energy:\s*([\d.eE+-]+)", "act_stdby_pj": r"ACT Stdby Energy:\s*([\d.eE+-]+)",
        "pre_stdby_pj": r"PRE Stdby Energy:\s*([\d.eE+-]+)", "total_pj": r"Total Trace Energy:\s*([\d.eE+-]+)",
    }
    tot = {k: 0.0 for k in pat}
    for p in paths:
        text = open(p).read()
        for k, r in pat.items():
            m = re.findall(r, text)
            if m:
                tot[k] += float(m[0])
    out = {"act_pre_pj": tot["act_pj"] + tot["pre_pj"], "rd_pj": tot["rd_pj"], "wr_pj": tot["wr_pj"],
           "ref_pj": tot["ref_pj"], "background_pj": tot["act_stdby_pj"] + tot["pre_stdby_pj"]}
    out["core_total_pj"] = sum(out.values())
    out["total_pj"] = tot["total_pj"]
    kv(out)


def main():
    a = sys.argv[1:]
    if not a:
        sys.exit(__doc__)
    c = a[0]
    if c == "ini":
        cmd_ini(a[1], a[2], a[3:])
    elif c == "dramsim3":
        cmd_dramsim3(*a[1:5])
    elif c == "tbdrsim-db":
        cmd_tbdrsim_db(*a[1:4])
    elif c == "drampower5":
        cmd_drampower5(a[1])
    elif c == "drampower4":
        cmd_drampower4(a[1:])
    else:
        sys.exit(f"unknown subcommand {c}\n{__doc__}")


if __name__ == "__main__":
    main()
