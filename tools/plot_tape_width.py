#!/usr/bin/python3
"""Paper 000's tape-width experiment (section 9), plotted: from bench_track_explore's --csv
(a row per run), per tape width the share of the network's edges track_explore found and
the false nodes it reported per 10 m of tape, pooled over layouts and starts.

    build/bench_track_explore --tape-mm 5,10,15,20,25,30 --layouts 101-103 --starts 20 \\
        --start-seed 7 --csv out/tape_width.csv
    tools/plot_tape_width.py out/tape_width.csv out/tape_width   # writes .svg and .png
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402


def pooled(rows):
    """Per tape width: edges found (%), runs with every edge (%), false nodes per 10 m."""
    by_width = defaultdict(lambda: defaultdict(float))
    for r in rows:
        w = by_width[float(r["tape_mm"])]
        w["runs"] += 1
        w["edges"] += int(r["edges"])
        w["visited"] += int(r["edges_visited"])
        w["complete"] += r["all_visited_s"] != ""
        w["false"] += int(r["false_nodes"])
        w["tape_m"] += float(r["tape_m"])
    widths = sorted(by_width)
    found = [100.0 * by_width[x]["visited"] / by_width[x]["edges"] for x in widths]
    complete = [100.0 * by_width[x]["complete"] / by_width[x]["runs"] for x in widths]
    false = [10.0 * by_width[x]["false"] / by_width[x]["tape_m"] for x in widths]
    return widths, found, complete, false


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        print(f"{argv[1]}: no runs", file=sys.stderr)
        return 1
    widths, found, complete, false = pooled(rows)
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
    top.plot(widths, found, "o-", label="edges found")
    top.plot(widths, complete, "s--", label="runs that found every edge")
    top.set_ylabel("%")
    top.set_ylim(0, 105)
    top.legend(loc="lower right")
    top.set_title("track_explore by tape width (%d runs)" % len(rows))
    bottom.plot(widths, false, "o-", color="tab:red")
    bottom.axhline(1.0, color="grey", linestyle=":", label="1 per 10 m")
    bottom.set_ylabel("false nodes per 10 m")
    bottom.set_xlabel("tape width, mm")
    bottom.legend(loc="upper right")
    for axis in (top, bottom):
        axis.grid(True, linewidth=0.3)
    fig.tight_layout()
    for ext in ("svg", "png"):
        fig.savefig(f"{argv[2]}.{ext}", dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
