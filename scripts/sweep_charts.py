#!/usr/bin/env python3
"""Charts of a sweep folder: MSE versus steps and MSE versus time, one line per method.

Usage: sweep_charts.py [--if-matplotlib] DIR

Reads DIR/results.csv (written by `reliefsim sweep` and `reliefsim merge`) and writes
DIR/mse_vs_steps.png and DIR/mse_vs_time.png, each with one panel per map and view. The
x axes are the measured average steps per pixel (avg_iterations) and the frame time in ms,
the y axis the dissertation's MSE (mse_paper), both logarithmic. A method whose `set`
crosses several keys gets one line per value of every varying key but the one with the
most values; the points of a line are joined in the order of x. Files are written to a temporary and
renamed, so a chart is either whole or absent. `reliefsim sweep` runs this script itself
(it is compiled into the binary) when python3 with matplotlib is installed.
Exit codes: 0 drawn, 1 bad input, 3 matplotlib is missing (silently with --if-matplotlib).
"""
import csv
import os
import sys

CHARTS = (("mse_vs_steps.png", "avg_iterations", "average steps per pixel", 1.0),
          ("mse_vs_time.png", "timing.frame_seconds", "frame time (ms)", 1e3))


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def read_rows(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or "method" not in rows[0] or "mse_paper" not in rows[0]:
        raise ValueError(path + ": not a sweep's results.csv")
    return rows


def panels(rows):
    """{(map, view): {line label: [row, ...]}}, in the order of first appearance."""
    out = {}
    set_keys = [k for k in rows[0].keys() if k.startswith("set.")]
    methods = {}
    for r in rows:
        methods.setdefault((r["map"], r["view"], r["method"]), []).append(r)
    for (m, v, method), group in methods.items():
        counts = {k: len({r[k] for r in group}) for k in set_keys}
        varying = [k for k in set_keys if counts[k] > 1]
        steps = max(varying, key=lambda k: counts[k], default=None)
        split = [k for k in varying if k != steps]
        lines = out.setdefault((m, v), {})
        for r in group:
            label = method + "".join(", %s=%s" % (k[4:], r[k] or "default") for k in split)
            lines.setdefault(label, []).append(r)
    return out


def draw(rows, directory, plt):
    groups = panels(rows)
    cols = min(3, len(groups))
    nrows = (len(groups) + cols - 1) // cols
    most = max(len(lines) for lines in groups.values())
    height = max(4.2, 0.17 * most + 1.0)
    styles = ["-", "--", ":", "-."]
    for name, xkey, xlabel, scale in CHARTS:
        fig, axes = plt.subplots(nrows, cols, figsize=(8.5 * cols, height * nrows),
                                 squeeze=False)
        for ax in axes.flat[len(groups):]:
            ax.set_visible(False)
        for ax, ((m, v), lines) in zip(axes.flat, groups.items()):
            for i, (label, members) in enumerate(lines.items()):
                pts = sorted((number(r[xkey]) * scale, number(r["mse_paper"])) for r in members
                             if number(r[xkey]) is not None and number(r["mse_paper"]) is not None)
                pts = [(x, y) for x, y in pts if x > 0 and y > 0]  # log axes
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", markersize=3,
                            color=plt.cm.tab10(i % 10), linestyle=styles[i // 10 % 4],
                            label=label)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("MSE (mse_paper)")
            ax.set_title("%s, view %s" % (m, v), fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
            if ax.lines:
                ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.tight_layout()
        final = os.path.join(directory, name)
        temp = os.path.join(directory, "." + name + ".tmp")
        fig.savefig(temp, format="png", dpi=100, metadata={"Software": None})
        plt.close(fig)
        os.replace(temp, final)


def main(argv):
    quiet = len(argv) == 3 and argv[1] == "--if-matplotlib"
    if quiet:
        argv = argv[:1] + argv[2:]
    if len(argv) != 2:
        print("usage: sweep_charts.py [--if-matplotlib] DIR", file=sys.stderr)
        return 1
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        if quiet:
            return 3
        print("sweep_charts.py: matplotlib is not installed (Debian: python3-matplotlib)",
              file=sys.stderr)
        return 3
    try:
        draw(read_rows(os.path.join(argv[1], "results.csv")), argv[1], plt)
    except (OSError, ValueError, KeyError) as e:
        print("sweep_charts.py: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
