"""Median planning time against joints and against obstacles (matplotlib, Agg backend)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["plot_scaling"]


def plot_scaling(rows: list[dict], path: Path) -> Path | None:
    """Write the two-panel PNG to ``path``; ``None`` when matplotlib is missing or nothing to plot."""
    try:
        import matplotlib
    except ImportError:
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("joints", "joints", "number of joints (joints_N: figure1's task, 1.7 m arm)"),
              ("obstacles", "obstacles", "number of obstacles (obstacles_M: 3 joints)")]
    panels = [p for p in panels if any(r["family"] == p[0] for r in rows)]
    if not panels:
        return None
    figure, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 3.9), squeeze=False)
    for axis, (family, key, label) in zip(axes[0], panels):
        group = sorted((r for r in rows if r["family"] == family), key=lambda r: r[key])
        x = [r[key] for r in group]
        axis.plot(x, [r["median_s"] for r in group], "o-", label="median (all runs)")
        axis.plot(x, [r["p90_s"] for r in group], "s--", alpha=0.6, label="p90")
        axis.plot(x, [r["median_cpu_s"] for r in group], "^:", alpha=0.8, label="median CPU time")
        for r in group:
            axis.annotate(f"{100 * r['success_rate']:.0f}%", (r[key], r["median_s"]), textcoords="offset points",
                          xytext=(4, 6), fontsize=8)
        limits = sorted({r["time_limit_s"] for r in group})
        for limit in limits:
            axis.axhline(limit, color="grey", linewidth=0.8, linestyle=":")
        axis.set_xscale("log" if family == "obstacles" else "linear")
        axis.set_xticks(x)
        axis.set_xticklabels([str(v) for v in x])
        axis.set_yscale("log")
        axis.set_xlabel(label)
        axis.set_ylabel("time per run (s)")
        seeds = sorted({r["seeds"] for r in group})
        axis.set_title(f"{family}: {'/'.join(map(str, seeds))} seeds; % = success; dotted = limit", fontsize=9)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8, loc="lower right")
    figure.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path
