"""Run the hard cases of tests/hard_cases.py in tamias2d and pymunk and
write the tables of docs/stability.md.

For every case: both engines with the default settings (10 iterations, one
step of 1/60 s per frame), the pass criterion, the numbers, and whether the
two final states are bitwise equal. For a case tamias2d fails, the settings
of hard_cases.FIX_GRID (and the case's own extra fixes) are tried in order
of added work until one passes; that setting is then run in pymunk too, and
its time is compared with the default time (time per simulated step, both
in tamias2d).

    PYTHONPATH=src:. python benchmarks/stability_report.py            # full runs
    PYTHONPATH=src:. python benchmarks/stability_report.py --ci       # CI lengths
    PYTHONPATH=src:. python benchmarks/stability_report.py --only stack_10 tunnel
    PYTHONPATH=src:. python benchmarks/stability_report.py --write docs/stability.md

With --write, the text between the markers ``<!-- results:begin -->`` and
``<!-- results:end -->`` of that file is replaced; without it the tables are
printed. --json FILE also saves the raw results (with the fixes found, for
hard_cases.FIXES).
"""
import argparse
import json
import os
import platform
import sys
import time

import pymunk
import tamias2d

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
import hard_cases as hc  # noqa: E402

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def fmt(v):
    if isinstance(v, float):
        if v == 0.0:
            return "0"
        if abs(v) >= 1e5 or abs(v) < 1e-3:
            return f"{v:.3g}"
        return f"{v:.4g}"
    return str(v)


def fmt_metrics(m):
    return "; ".join(f"{k} {fmt(v)}" for k, v in m.items())


def outcome(r):
    if r.error:
        return "error: " + r.error
    if r.nan:
        return "FAIL (NaN)"
    return "pass" if r.passed else "FAIL"


def settings_text(s):
    parts = []
    if s.get("iterations", 10) != 10:
        parts.append(f"iterations {s['iterations']}")
    if s.get("substeps", 1) != 1:
        parts.append(f"{s['substeps']} substeps (dt 1/{60 * s['substeps']})")
    if "slop" in s:
        parts.append(f"collision_slop {s['slop']:g}")
    return ", ".join(parts) or "defaults"


def per_step(r):
    n = r.stopped_at or r.steps
    return r.seconds / max(n, 1)


def study(case, full, log):
    row = {"case": case.name}
    res = {}
    for mod in (tamias2d, pymunk):
        t0 = time.perf_counter()
        res[mod.__name__] = hc.run_case(mod, case, full=full)
        log(f"  {case.name} {mod.__name__}: {outcome(res[mod.__name__])} "
            f"({time.perf_counter() - t0:.1f} s)")
    t, p = res["tamias2d"], res["pymunk"]
    row.update(default_t=t, default_p=p, same=(t.hash == p.hash and t.steps == p.steps))
    row["fix"] = None
    if not t.passed:
        for setting in list(case.extra_fixes) + hc.FIX_GRID:
            r = hc.run_case(tamias2d, case, full=full, stop_early=True, **setting)
            log(f"    try {settings_text(setting)}: {outcome(r)}"
                + (f" (stopped at step {r.stopped_at})" if r.stopped_at else ""))
            if r.passed:
                rp = hc.run_case(pymunk, case, full=full, **setting)
                row["fix"] = dict(setting=setting, t=r, p=rp, same=(r.hash == rp.hash),
                                  cost=per_step(r) / per_step(t))
                break
    return row


def tables(rows, full, total):
    out = []
    mode = "full" if full else "CI (reduced)"
    out.append(f"Run: {mode} lengths, {time.strftime('%Y-%m-%d')}, tamias2d {tamias2d.version}, "
               f"pymunk {pymunk.version}, Python {platform.python_version()}, "
               f"{platform.machine()}; whole run {total:.0f} s.")
    out.append("")
    out.append("### Default settings (10 iterations, dt 1/60)")
    out.append("")
    out.append("| case | steps | criterion | tamias2d | pymunk | bitwise equal | numbers (tamias2d) |")
    out.append("|---|---|---|---|---|---|---|")
    for row in rows:
        c = hc.CASES[row["case"]]
        t, p = row["default_t"], row["default_p"]
        out.append(f"| `{c.name}`: {c.title} | {t.steps:,} | {c.criterion} | {outcome(t)} | "
                   f"{outcome(p)} | {'yes' if row['same'] else 'NO'} | {fmt_metrics(t.metrics)} |")
    out.append("")
    failing = [r for r in rows if not r["default_t"].passed]
    if failing:
        out.append("### Cases that fail with the defaults: what makes them pass")
        out.append("")
        out.append("Settings tried in order of added work (see `FIX_GRID` in tests/hard_cases.py); "
                   "the first that passes is shown. Cost: time per simulated step with that "
                   "setting / with the defaults, in tamias2d.")
        out.append("")
        out.append("| case | setting that passes | tamias2d | pymunk | bitwise equal | "
                   "cost (time x) | ms per 1/60 s, default -> fixed | numbers (tamias2d) |")
        out.append("|---|---|---|---|---|---|---|---|")
        for row in failing:
            c = hc.CASES[row["case"]]
            fx = row["fix"]
            if fx is None:
                out.append(f"| `{c.name}` | none of the grid; {c.note or 'no setting found'} | FAIL | "
                           f"FAIL | | | | |")
                continue
            t, p = fx["t"], fx["p"]
            out.append(f"| `{c.name}` | {settings_text(fx['setting'])} | {outcome(t)} | {outcome(p)} | "
                       f"{'yes' if fx['same'] else 'NO'} | {fx['cost']:.1f} | "
                       f"{per_step(row['default_t']) * 1e3:.3f} -> {per_step(t) * 1e3:.3f} | "
                       f"{fmt_metrics(t.metrics)} |")
        out.append("")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="the reduced (CI) lengths")
    ap.add_argument("--only", nargs="*", help="case names")
    ap.add_argument("--write", help="markdown file whose results section to replace")
    ap.add_argument("--json", help="save raw results here")
    args = ap.parse_args(argv)
    names = args.only or list(hc.CASES)
    full = not args.ci
    t0 = time.perf_counter()
    rows = []
    for name in names:
        print(f"{name} ...", file=sys.stderr, flush=True)
        rows.append(study(hc.CASES[name], full, lambda s: print(s, file=sys.stderr, flush=True)))
    text = tables(rows, full, time.perf_counter() - t0)
    if args.json:
        def res(r):
            return None if r is None else dict(passed=r.passed, nan=r.nan, metrics=r.metrics,
                                               hash=r.hash, seconds=r.seconds, steps=r.steps,
                                               settings=r.settings, error=r.error,
                                               stopped_at=r.stopped_at)
        data = []
        for row in rows:
            fx = row["fix"]
            data.append(dict(case=row["case"], tamias2d=res(row["default_t"]),
                             pymunk=res(row["default_p"]), same=row["same"],
                             fix=None if fx is None else dict(setting=fx["setting"], same=fx["same"],
                                                              cost=fx["cost"], tamias2d=res(fx["t"]),
                                                              pymunk=res(fx["p"]))))
        with open(args.json, "w") as f:
            json.dump(data, f, indent=1)
    if args.write:
        with open(args.write) as f:
            doc = f.read()
        a, b = doc.index(BEGIN) + len(BEGIN), doc.index(END)
        with open(args.write, "w") as f:
            f.write(doc[:a] + "\n" + text + "\n" + doc[b:])
    else:
        print(text)


if __name__ == "__main__":
    main()
