"""The hard cases (tests/hard_cases.py) in the soft solver at its defaults,
beside the chipmunk solver's documented outcome (hard_cases.FULL_DEFAULT,
which is pymunk's too: the two are bitwise equal), as the table of
docs/stability.md "The soft solver".

    PYTHONPATH=src:tests python benchmarks/soft_stability.py          # full lengths
    PYTHONPATH=src:tests python benchmarks/soft_stability.py --ci     # CI lengths
    PYTHONPATH=src:tests python benchmarks/soft_stability.py --only stack_40 arch
"""
import argparse
import time

import tamias2d
import hard_cases as hc


from stability_report import fmt  # noqa: E402 (the same number format)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ci", action="store_true", help="CI lengths instead of the full ones")
    ap.add_argument("--only", nargs="*", help="these cases only")
    args = ap.parse_args()
    names = args.only or list(hc.CASES)
    rows = []
    soft_passes = chip_passes = 0
    for name in names:
        case = hc.CASES[name]
        t0 = time.perf_counter()
        r = hc.run_case(tamias2d, case, full=not args.ci, solver="soft")
        if args.ci:
            chip = hc.run_case(tamias2d, case).passed
        else:
            chip = hc.FULL_DEFAULT[name]
        soft_passes += r.passed
        chip_passes += chip
        if r.error:
            soft = "error: " + r.error
        elif r.nan:
            soft = "FAIL (NaN)"
        else:
            soft = "**pass**" if r.passed and not chip else ("pass" if r.passed else "FAIL")
        numbers = "; ".join(f"{k} {fmt(v)}" for k, v in r.metrics.items())
        rows.append(f"| `{name}` | {'pass' if chip else 'FAIL'} | {soft} | {numbers} |")
        print(f"{name}: {soft} ({time.perf_counter() - t0:.1f} s)", flush=True)
    print()
    print("| hard case | chipmunk solver (= pymunk) | soft solver | soft solver numbers |")
    print("|---|---|---|---|")
    print("\n".join(rows))
    print()
    print(f"chipmunk solver: {chip_passes} of {len(names)} pass; soft solver: "
          f"{soft_passes} of {len(names)}.")


if __name__ == "__main__":
    main()
