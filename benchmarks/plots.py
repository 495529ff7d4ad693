"""PNG plots of a benchmark run (matplotlib, imported only here).

    scene-ratios.png    tamias2d / pymunk step time per scene and size
    scaling.png         step time and time per body against body count
    speed-vs-error.png  error against time per simulated second, one
                        panel per case and metric, the best front outlined
"""
import os

COLORS = {"pymunk": "#1f77b4", "tamias2d": "#d62728"}
STYLE = {"pymunk": "--", "tamias2d": "-"}
ERROR_FLOOR = 1e-17


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _stamp(fig, results):
    m = results.get("meta", {}).get("machine", {})
    text = (f"{m.get('cpu', '?')}, {m.get('logical_cpus', '?')} logical CPUs, Python {m.get('python', '?')}, "
            f"tamias2d {m.get('tamias2d', '?')}, pymunk {m.get('pymunk', '?')}")
    if results.get("meta", {}).get("quick"):
        text += "  (--quick run: tiny sizes, not for reading)"
    fig.text(0.01, 0.005, text, fontsize=7, color="0.4", ha="left", va="bottom")


def plot_scene_ratios(results, path):
    rows = results.get("scenes") or []
    if not rows:
        return None
    plt = _plt()
    labels = [f"{r['scene']} {r['size']} {r['unit']}" for r in rows]
    ratios = [r["ratio"] for r in rows]
    fig, ax = plt.subplots(figsize=(7.5, 0.32 * len(rows) + 1.4))
    y = list(range(len(rows)))[::-1]
    colors = [COLORS["tamias2d"] if q < 1.0 else COLORS["pymunk"] for q in ratios]
    ax.barh(y, ratios, color=colors, alpha=0.8)
    ax.axvline(1.0, color="k", lw=1)
    for yi, q in zip(y, ratios):
        ax.text(q, yi, f" {q:.2f}", va="center", fontsize=8)
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=8)
    ax.set_xlabel("step time, tamias2d / pymunk (below 1: tamias2d faster)")
    ax.set_xlim(0, max(1.3, max(ratios) * 1.15))
    ax.set_title("Step time ratio per scene (median of alternating blocks)", fontsize=10)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    _stamp(fig, results)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_scaling(results, path):
    rows = results.get("scaling") or []
    if not rows:
        return None
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.4))
    markers = {"box wall": "s", "sparse field": "o"}
    for scene in sorted({r["scene"] for r in rows}):
        pts = sorted((r for r in rows if r["scene"] == scene), key=lambda r: r["bodies"])
        xs = [r["bodies"] for r in pts]
        for e in ("pymunk", "tamias2d"):
            ax1.plot(xs, [r[f"{e}_ms"] for r in pts], STYLE[e], marker=markers.get(scene, "^"),
                     color=COLORS[e], label=f"{e}, {scene}")
            ax2.plot(xs, [r[f"{e}_ms"] * 1e3 / r["bodies"] for r in pts], STYLE[e],
                     marker=markers.get(scene, "^"), color=COLORS[e], label=f"{e}, {scene}")
    lo = min(r["bodies"] for r in rows)
    hi = max(r["bodies"] for r in rows)
    base = min(r["tamias2d_ms"] for r in rows if r["bodies"] == lo)
    ax1.plot([lo, hi], [base, base * hi / lo], ":", color="0.5", label="linear growth")
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    ax1.set_xlabel("bodies")
    clock = "CPU" if results.get("meta", {}).get("clock") == "cpu" else "wall"
    ax1.set_ylabel(f"ms per step ({clock} time)")
    ax1.set_title("Step time against body count", fontsize=10)
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=7)
    ax2.set_xscale("log")
    ax2.set_xlabel("bodies")
    ax2.set_ylabel("microseconds per body per step")
    ax2.set_title("Cost per body (flat = linear scaling)", fontsize=10)
    ax2.set_ylim(bottom=0)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=7)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    _stamp(fig, results)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_speed_vs_error(results, path):
    acc = results.get("accuracy") or {}
    rows = acc.get("rows") or []
    if not rows:
        return None
    plt = _plt()
    keys = []
    for r in rows:
        k = (r["case"], r["metric"])
        if k not in keys:
            keys.append(k)
    ncols = 3
    nrows = (len(keys) + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(13, 3.6 * nrows), squeeze=False)
    its = sorted({r["iterations"] for r in rows})
    cmap = plt.get_cmap("viridis")
    shade = {it: cmap(0.15 + 0.7 * i / max(1, len(its) - 1)) for i, it in enumerate(its)}
    fronts = acc.get("front", {})
    for ax, (case, metric) in zip(axes.flat, keys):
        pts = [r for r in rows if r["case"] == case and r["metric"] == metric]
        for e in ("pymunk", "tamias2d"):
            for it in its:
                # joined in time-step order, largest step first
                curve = sorted((r for r in pts if r["engine"] == e and r["iterations"] == it),
                               key=lambda r: -r["dt"])
                if not curve:
                    continue
                ax.plot([r["cost"] * 1e3 for r in curve],
                        [max(r["error"], ERROR_FLOOR) for r in curve],
                        STYLE[e], marker="o" if e == "tamias2d" else "x", ms=4,
                        color=shade[it], label=f"{e}, {it} it." if ax is axes.flat[0] else None)
        front = fronts.get(f"{case} / {metric}", [])
        if front:
            ax.step([f["cost"] * 1e3 for f in front], [max(f["error"], ERROR_FLOOR) for f in front],
                    where="post", color="k", lw=0.8, alpha=0.6)
            ax.plot([f["cost"] * 1e3 for f in front], [max(f["error"], ERROR_FLOOR) for f in front],
                    "o", mfc="none", mec="k", ms=8)
        unit = pts[0]["unit"]
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log_ticks(ax)
        ax.set_title(f"{case}: {metric}", fontsize=10)
        clock = "CPU" if results.get("meta", {}).get("clock") == "cpu" else "wall"
        ax.set_xlabel(f"ms of {clock} time per simulated second", fontsize=8)
        ax.set_ylabel(f"error ({unit})", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, which="both", alpha=0.25)
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    dts = acc.get("meta", {}).get("dts", [])
    fig.legend(handles, labels, loc="upper center", ncol=min(len(labels), 8), fontsize=8,
               title=("points along a curve: time steps "
                      + ", ".join(f"1/{round(1 / d)}" for d in sorted(dts, reverse=True))
                      + " (largest first, usually left to right); circled and joined by the "
                      "thin black line: the best front of the panel (errors of 0 drawn at 1e-17)"),
               title_fontsize=8)
    fig.tight_layout(rect=(0, 0.03, 1, 0.93))
    _stamp(fig, results)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def _plain_log_ticks(ax):
    """Decade labels only, as plain numbers (the default minor labels of a
    narrow log axis overlap)."""
    from matplotlib import ticker
    fmt = ticker.FuncFormatter(lambda v, _: f"{v:g}")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(ticker.LogLocator(base=10, numticks=12))
        axis.set_minor_locator(ticker.LogLocator(base=10, subs=tuple(range(2, 10)), numticks=12))
        axis.set_minor_formatter(ticker.NullFormatter())
    ax.xaxis.set_major_formatter(fmt)
    ax.yaxis.set_major_formatter(ticker.LogFormatterSciNotation())


def write_all(results, folder):
    os.makedirs(folder, exist_ok=True)
    made = []
    for name, func in (("scene-ratios.png", plot_scene_ratios), ("scaling.png", plot_scaling),
                       ("speed-vs-error.png", plot_speed_vs_error)):
        out = func(results, os.path.join(folder, name))
        if out:
            made.append(out)
    return made
