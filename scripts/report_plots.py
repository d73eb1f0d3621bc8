#!/usr/bin/env python3
"""Plots for the `clutterseg eval` report, drawn with matplotlib from the files eval writes.

usage: report_plots.py OUT_DIR   (reads OUT_DIR/summary.json and OUT_DIR/scenes.csv, writes OUT_DIR/plots/*.svg)

`clutterseg eval` runs this script itself; run it by hand to redraw the plots of an earlier evaluation.
Exit code 3 means matplotlib is missing (the report then says so and shows the tables only).
"""
import csv
import json
import math
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")  # files only, no display
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed (Debian: apt-get install python3-matplotlib)", file=sys.stderr)
    sys.exit(3)

plt.rcParams.update({"svg.hashsalt": "clutterseg", "font.size": 9, "axes.grid": True, "grid.alpha": 0.3})
MARKERS = "osD^v<>PX*"


def number(text):
    try:
        v = float(text)
        return v if math.isfinite(v) else None
    except (TypeError, ValueError):
        return None


def shown_runs(summary):
    """The run of each method shown in the report: its default, or the best value of a sweep."""
    return [r for r in summary["runs"] if r.get("shown")]


def scatter(summary, rows, path):
    """Per frame tp against fp, one colour per method and one marker per family (the paper's Fig. 8)."""
    runs = shown_runs(summary)
    families = sorted({row["family"] for row in rows})
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for k, run in enumerate(runs):
        colour = f"C{k}"
        for f, family in enumerate(families):
            pts = [(number(r["fp"]), number(r["tp"])) for r in rows
                   if r["run"] == run["label"] and r["family"] == family]
            pts = [(100 * x, 100 * y) for x, y in pts if x is not None and y is not None]
            if not pts:
                continue
            label = run["label"] if len(families) == 1 else f"{run['label']} / {family}"
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=28, color=colour,
                       marker=MARKERS[f % len(MARKERS)], alpha=0.8, label=label, edgecolors="none")
    ax.set_xlabel("false positive fp [%] (paper, per frame)")
    ax.set_ylabel("true positive tp [%] (paper, per frame)")
    ax.set_xlim(-2, 102)
    ax.set_ylim(-2, 102)
    ax.set_title("Per-frame paper scores (ideal: top left)")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def timings(summary, path):
    """Mean time per pipeline stage and method, stacked (the paper's Table III)."""
    runs = [r for r in shown_runs(summary) if r.get("timings_ms")]
    if not runs:
        return False
    stages = []
    for run in runs:
        for name, _ in run["timings_ms"]:
            if name != "total" and name not in stages:
                stages.append(name)
    fig, ax = plt.subplots(figsize=(6.4, max(1.2 + 0.45 * len(runs), 0.3 + 0.2 * len(stages))))
    ys = range(len(runs))
    left = [0.0] * len(runs)
    cmap = plt.get_cmap("tab20")
    for s, stage in enumerate(stages):
        widths = [dict(run["timings_ms"]).get(stage, 0.0) for run in runs]
        ax.barh(list(ys), widths, left=left, color=cmap(s % 20), label=stage, height=0.6)
        left = [a + b for a, b in zip(left, widths)]
    for y, run in zip(ys, runs):
        total = dict(run["timings_ms"]).get("total", left[y])
        ax.text(left[y], y, f"  {total:.1f} ms", va="center", fontsize=8)
    ax.set_yticks(list(ys), [r["label"] for r in runs])
    ax.invert_yaxis()
    ax.set_xlabel("mean time per frame [ms]")
    ax.set_xlim(0, max(left) * 1.25 if max(left) > 0 else 1)
    ax.set_title("Time per stage (mean over frames)")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=7, frameon=False)
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return True


def families(summary, path):
    """Overlap F and paper tp per family and method (the layout of the paper's Table II)."""
    runs = shown_runs(summary)
    names = []
    for run in runs:
        for g in run["groups"]:
            if g["family"] not in names:
                names.append(g["family"])
    fig, ax = plt.subplots(figsize=(6.4, 3.2))
    width = 0.8 / max(1, 2 * len(runs))
    for k, run in enumerate(runs):
        groups = {g["family"]: g for g in run["groups"]}
        for m, (metric, hatch) in enumerate((("tp", ""), ("overlap_f", "//"))):
            xs, hs = [], []
            for i, name in enumerate(names):
                v = groups.get(name, {}).get("scores", {}).get(metric, {}).get("mean")
                if v is not None:
                    xs.append(i + (2 * k + m - len(runs) + 0.5) * width)
                    hs.append(100 * v)
            ax.bar(xs, hs, width=width, color=f"C{k}", hatch=hatch, edgecolor="white",
                   label=f"{run['label']}: {'tp' if metric == 'tp' else 'Overlap F'}")
    ax.set_xticks(range(len(names)), names)
    ax.set_ylim(0, 105)
    ax.set_ylabel("[%]")
    ax.set_title("Per family: paper tp and UOIS Overlap F")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)


RECALL_PARTS = (("boundary", "boundary"), ("dropped", "dropped"), ("split", "split off"), ("merged", "merged away"))
PRECISION_PARTS = (("boundary_p", "boundary"), ("background", "table/background"), ("merged_p", "other object"),
                   ("extra", "extra segments"))


def errors(summary, path):
    """Where the errors are, per family and method: the lost shares of recall and of precision, stacked."""
    bars = []  # (label, group errors)
    for run in shown_runs(summary):
        for g in run["groups"]:
            if g.get("errors") and g["errors"].get("kept") is not None:
                name = g["family"] if len(shown_runs(summary)) == 1 else f"{run['label']} / {g['family']}"
                bars.append((name, g["errors"]))
    if not bars:
        return False
    fig, axes = plt.subplots(1, 2, figsize=(9.6, 0.8 + 0.32 * len(bars)), sharey=True)
    ys = range(len(bars))
    for ax, parts, title in ((axes[0], RECALL_PARTS, "recall lost [% of ground-truth object pixels]"),
                             (axes[1], PRECISION_PARTS, "precision lost [% of predicted object pixels]")):
        left = [0.0] * len(bars)
        for k, (key, label) in enumerate(parts):
            widths = [100 * (e.get(key) or 0.0) for _, e in bars]
            ax.barh(ys, widths, left=left, color=f"C{k}", label=label, height=0.7)
            left = [a + b for a, b in zip(left, widths)]
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    axes[0].set_yticks(list(ys), [name for name, _ in bars])
    axes[0].invert_yaxis()
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return True


def sweep(summary, path):
    """Scores over the swept parameter values; the best by Overlap F is marked."""
    info = summary.get("sweep")
    if not info:
        return False
    param = info["parameter"]
    runs = [r for r in summary["runs"] if param in r.get("setting", {})]
    if not runs:
        return False
    fig, ax = plt.subplots(figsize=(6.4, 3.4))
    xs = [r["setting"][param] for r in runs]
    overall = [{g["family"]: g for g in r["groups"]}["all"]["scores"] for r in runs]
    for metric, label in (("overlap_f", "Overlap F"), ("boundary_f", "Boundary F"), ("tp", "tp (paper)"),
                          ("fp", "fp (paper)")):
        ys = [s[metric]["mean"] for s in overall]
        ax.plot(xs, [100 * y if y is not None else float("nan") for y in ys], marker="o", label=label)
    for r, x in zip(runs, xs):
        if r.get("best"):
            ax.axvline(x, color="grey", linestyle="--", linewidth=1)
            ax.annotate("best", (x, 100), textcoords="offset points", xytext=(3, -10), fontsize=8)
    ax.set_xlabel(param)
    ax.set_ylabel("[%]")
    ax.set_ylim(0, 105)
    ax.set_title(f"Sweep of {param} (all frames)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return True


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    out = sys.argv[1]
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    with open(os.path.join(out, "scenes.csv"), encoding="utf-8", newline="") as f:
        rows = list(csv.DictReader(f))
    plots = os.path.join(out, "plots")
    os.makedirs(plots, exist_ok=True)
    scatter(summary, rows, os.path.join(plots, "scatter.svg"))
    families(summary, os.path.join(plots, "families.svg"))
    timings(summary, os.path.join(plots, "timings.svg"))
    errors(summary, os.path.join(plots, "errors.svg"))
    sweep(summary, os.path.join(plots, "sweep.svg"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
