"""Median planning time against joints and against obstacles (matplotlib, Agg backend)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["plot_scaling"]

PANELS = (
    ("joints", "number of joints (joints_N: figure1's task, 1.7 m arm split in N links)"),
    ("obstacles", "number of obstacles (obstacles_M: joints_3 + M - 2 boxes)"),
)


def plot_scaling(rows: list[dict], path: Path) -> Path | None:
    """Write the two-panel PNG to ``path``; ``None`` when matplotlib is missing or nothing to plot.

    ``rows`` are the summary rows of :mod:`benchmarks.run`; the ``joints`` and
    ``obstacles`` series are plotted (a panel without rows says so).
    """
    try:
        import matplotlib
    except ImportError:
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in rows if r.get("median_s") is not None]
    if not any(r.get("series") in ("joints", "obstacles") for r in rows):
        return None
    figure, axes = plt.subplots(1, 2, figsize=(10.4, 4.0), squeeze=False)
    for axis, (series, label) in zip(axes[0], PANELS, strict=True):
        group = sorted((r for r in rows if r.get("series") == series), key=lambda r: r[series])
        _panel(axis, series, label, group)
    figure.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def _panel(axis: Any, series: str, label: str, group: list[dict]) -> None:
    """One panel: the ``series`` worlds' rows ``group``, sorted by joints or obstacles (or a note that there
    are none)."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    plain = FuncFormatter(lambda value, _pos: f"{value:g}")
    # minor ticks of a log axis: label 2 and 5 (x 10^k) only
    sparse = FuncFormatter(lambda value, _pos: f"{value:g}" if f"{value:.0e}"[0] in "25" else "")
    axis.set_xlabel(label, fontsize=9)
    axis.set_ylabel("time per run (s)")
    if not group:
        axis.text(0.5, 0.5, f"no {series}_* world in this run", ha="center", va="center", transform=axis.transAxes)
        axis.set_xticks([])
        axis.set_yticks([])
        return
    x = [r[series] for r in group]
    axis.plot(x, [r["median_s"] for r in group], "o-", label="median wall, all runs")
    axis.plot(x, [r["p90_s"] for r in group], "s--", alpha=0.6, label="p90 wall, all runs")
    axis.plot(x, [r["median_cpu_s"] for r in group], "^:", alpha=0.8, label="median CPU, all runs")
    ok = [(r[series], r["median_success_s"]) for r in group if r.get("median_success_s") is not None]
    if ok:
        axis.plot(*zip(*ok, strict=True), "D", color="tab:green", alpha=0.8, label="median wall, successful runs")
    for r in group:
        axis.annotate(
            f"{100 * r['success_rate']:.0f}%",
            (r[series], r["median_s"]),
            textcoords="offset points",
            xytext=(4, 6),
            fontsize=8,
        )
    limits = sorted({r["time_limit_s"] for r in group})
    for limit in limits:
        axis.axhline(limit, color="grey", linewidth=0.8, linestyle=":")
    values = [v for r in group for v in (r["median_s"], r["p90_s"], r["median_cpu_s"], r.get("median_success_s")) if v]
    axis.set_yscale("log")
    axis.set_ylim(min(values + limits) / 2, max(values + limits) * 2)
    axis.yaxis.set_major_formatter(plain)
    low, high = min(values + limits) / 2, max(values + limits) * 2
    axis.yaxis.set_minor_formatter(plain if high / low < 10 else sparse)
    if series == "obstacles":
        axis.set_xscale("log")
    axis.set_xticks(x)
    axis.xaxis.set_major_formatter(plain)
    axis.xaxis.set_minor_formatter(NullFormatter())
    axis.set_xlim(
        min(x) / 1.3 if series == "obstacles" else min(x) - 0.5, max(x) * 1.3 if series == "obstacles" else max(x) + 0.5
    )
    seeds = sorted({r["seeds"] for r in group})
    axis.set_title(
        f"{series}: {'/'.join(map(str, seeds))} seeds per world; % = success; dotted = time limit", fontsize=9
    )
    axis.grid(True, which="both", alpha=0.3)
    axis.legend(fontsize=7, loc="lower right")
