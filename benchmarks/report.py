"""Markdown tables (and plots) from the JSON of a benchmark run.

    python benchmarks/report.py RESULTS.json [--plots DIR]

prints the tables that docs/benchmarks.md shows; ``run.py --markdown PATH``
writes the same text at the end of a run.
"""
import argparse
import json
import os
import statistics
import sys


def _num(x, digits=3):
    if x is None:
        return "n/a"
    if x == 0:
        return "0"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{digits}g}"


def _err(x):
    if x is None:
        return "n/a"
    if x == 0:
        return "0"
    return f"{x:.2g}"


def _table(header, rows, align=None):
    """A Markdown table; `align` has one letter per column, l or r (default:
    the first column left, the others right)."""
    align = align or "l" + "r" * (len(header) - 1)
    out = ["| " + " | ".join(header) + " |",
           "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"]
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    return "\n".join(out)


def machine(results):
    meta = results.get("meta", {})
    m = meta.get("machine", {})
    lines = [
        f"- CPU: {m.get('cpu', '?')} ({m.get('logical_cpus', '?')} logical CPUs)",
        f"- Memory: {round(m['memory_kb'] / 1024 / 1024, 1)} GiB" if "memory_kb" in m else None,
        f"- OS: {m.get('platform', '?')}",
        f"- Python {m.get('python', '?')} ({m.get('python_implementation', '?')}), "
        f"NumPy {m.get('numpy', '?')}, Cython {m.get('cython', '?')}",
        f"- tamias2d {m.get('tamias2d', '?')} (built with -O3 -ffp-contract=off), "
        f"pymunk {m.get('pymunk', '?')} (Chipmunk {m.get('chipmunk_of_pymunk', '?')}, from its wheel)",
        f"- Command: `{meta.get('command', '?')}`, {meta.get('started', '?')}, "
        f"{meta.get('duration_s', 0):.0f} s",
    ]
    if meta.get("clock") == "cpu":
        lines.append("- Clock: CPU time of the benchmark process (`--clock cpu`), not elapsed time")
    elif meta.get("clock") == "wall":
        lines.append("- Clock: elapsed wall time")
    if meta.get("load_average_start") and meta.get("load_average_end"):
        lines.append("- Load average (1 min) at the start and the end: "
                     f"{meta['load_average_start'][0]:.2f}, {meta['load_average_end'][0]:.2f}")
    return "\n".join(x for x in lines if x)


def scenes_table(results):
    rows = results.get("scenes") or []
    if not rows:
        return ""
    out = []
    for r in rows:
        extra = ""
        if "callbacks_per_step" in r:
            extra = f" ({r['callbacks_per_step']:.0f} callbacks/step)"
        out.append([r["scene"] + extra, f"{r['size']} {r['unit']}", r["bodies"], r["contacts"],
                    _num(r["pymunk_ms"]), _num(r["tamias2d_ms"]), f"{r['ratio']:.2f}",
                    "yes" if r["same_motion"] else "**no**"])
    ratios = [r["ratio"] for r in rows]
    text = _table(["scene", "size", "bodies", "contacts", "pymunk ms/step", "tamias2d ms/step",
                   "ratio", "same motion"], out, "llrrrrrl")
    text += (f"\n\nGeometric mean of the ratios: {statistics.geometric_mean(ratios):.2f} "
             f"(range {min(ratios):.2f} to {max(ratios):.2f}).")
    return text


def scaling_table(results):
    rows = results.get("scaling") or []
    if not rows:
        return ""
    out = [[r["scene"], r["bodies"], r["contacts"], _num(r["pymunk_ms"]), _num(r["tamias2d_ms"]),
            f"{r['ratio']:.2f}", _num(r["pymunk_us_per_body"]), _num(r["tamias2d_us_per_body"])]
           for r in rows]
    return _table(["scene", "bodies", "contacts", "pymunk ms/step", "tamias2d ms/step", "ratio",
                   "pymunk us/body", "tamias2d us/body"], out)


def accuracy_tables(results):
    acc = results.get("accuracy") or {}
    rows = acc.get("rows") or []
    if not rows:
        return ""
    meta = acc.get("meta", {})
    its = meta.get("iterations") or sorted({r["iterations"] for r in rows})
    dts = meta.get("dts") or sorted({r["dt"] for r in rows}, reverse=True)
    keys = []
    for r in rows:
        if (r["case"], r["metric"]) not in keys:
            keys.append((r["case"], r["metric"]))
    index = {(r["case"], r["metric"], r["engine"], r["dt"], r["iterations"]): r for r in rows}

    # errors (the same in both engines unless marked)
    err_rows = []
    for case, metric in keys:
        for dt in dts:
            cells = []
            for it in its:
                p = index.get((case, metric, "pymunk", dt, it))
                t = index.get((case, metric, "tamias2d", dt, it))
                if p is None or t is None:
                    cells.append("")
                elif p["error"] == t["error"]:
                    cells.append(_err(t["error"]))
                else:
                    cells.append(f"{_err(t['error'])} (pymunk {_err(p['error'])})")
            unit = index[(case, metric, "tamias2d", dts[0], its[0])]["unit"]
            err_rows.append([f"{case}: {metric} ({unit})", f"1/{round(1 / dt)}"] + cells)
    text = "#### Error by setting\n\n" + _table(
        ["case: metric (unit)", "dt"] + [f"{it} iterations" for it in its], err_rows)

    # cost
    cost_rows = []
    for case in dict.fromkeys(k[0] for k in keys):
        metric = next(m for c, m in keys if c == case)
        pick = [(dt, it) for dt in dts for it in its]
        ratios = [index[(case, metric, "tamias2d", dt, it)]["cost"]
                  / index[(case, metric, "pymunk", dt, it)]["cost"] for dt, it in pick]
        d60 = min(dts, key=lambda d: abs(d - 1 / 60))
        i10 = min(its, key=lambda i: abs(i - 10))
        p = index[(case, metric, "pymunk", d60, i10)]
        t = index[(case, metric, "tamias2d", d60, i10)]
        cost_rows.append([case, _num(p["cost"] * 1e3), _num(t["cost"] * 1e3),
                          f"{t['cost'] / p['cost']:.2f}", f"{statistics.median(ratios):.2f}",
                          f"{min(ratios):.2f} to {max(ratios):.2f}"])
    clock = "CPU" if results.get("meta", {}).get("clock") == "cpu" else "wall"
    text += (f"\n\n#### Cost\n\nMilliseconds of {clock} time per simulated second at dt = 1/"
             f"{round(1 / d60)} and {i10} iterations, and the tamias2d/pymunk cost ratio over "
             "all settings.\n\n" + _table(
                 ["case", "pymunk ms/s", "tamias2d ms/s", "ratio", "median ratio, all settings",
                  "range"], cost_rows))

    # best fronts
    fr_rows = []
    for key, front in (acc.get("front") or {}).items():
        pts = "; ".join(f"{f['engine']} 1/{round(1 / f['dt'])} {f['iterations']} it. "
                        f"({_num(f['cost'] * 1e3)} ms/s, {_err(f['error'])})" for f in front)
        fr_rows.append([key, pts])
    text += ("\n\n#### Best front\n\nThe settings that no other setting (of either engine) "
             "beats on both cost and error, cheapest first.\n\n"
             + _table(["case / metric", "settings on the front (cost, error)"], fr_rows, "ll"))
    return text


def operations_table(results):
    rows = results.get("operations") or []
    if not rows:
        return ""
    out = []
    for r in rows:
        ratio = "n/a" if r["ratio"] is None else f"{r['ratio']:.3g}"
        tam = _num(r["tamias2d_ms"]) if r["status"] == "ok" else r["status"]
        note = r["note"]
        if "pymunk_us_per_callback" in r:
            per = [_num(r[f"{e}_us_per_callback"]) + " us" if r[f"{e}_us_per_callback"] > 0
                   else "below the noise" for e in ("pymunk", "tamias2d")]
            note += f"; added cost per callback: pymunk {per[0]}, tamias2d {per[1]}"
        out.append([r["operation"], r["n"], _num(r["pymunk_ms"]), tam, ratio, note])
    return _table(["operation", "n", "pymunk ms", "tamias2d ms", "ratio", "what is timed"], out,
                  "lrrrrl")


def markdown(results):
    parts = ["### Machine\n\n" + machine(results)]
    for title, func in (("Scenes", scenes_table), ("Scaling", scaling_table),
                        ("Speed against error", accuracy_tables),
                        ("Operations", operations_table)):
        body = func(results)
        if body:
            parts.append(f"### {title}\n\n{body}")
    return "\n\n".join(parts) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="JSON written by run.py --json")
    parser.add_argument("--plots", metavar="DIR", help="also write the PNG plots into DIR")
    args = parser.parse_args(argv)
    with open(args.results) as f:
        results = json.load(f)
    sys.stdout.write(markdown(results))
    if args.plots:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import plots
        for path in plots.write_all(results, args.plots):
            print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
