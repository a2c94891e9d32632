"""A convoy over seeds, from Python: how often and how fast eight Kheperas form a convoy,
with rilbed's C++ convoy and with its Python port, plotted with matplotlib.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/convoy_over_seeds.py --seeds 20 --plot convoy.png

Each run goes through the same run session as `rilbed run --fast --stop-when-formed`;
its summary comes back as a dict. Prints a table (Markdown) and saves the plot.
"""

import argparse
import os
import statistics

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402

import rilbed  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SCENARIOS = os.path.join(HERE, "..", "..", "scenarios")
CONTROLLERS = {"C++ convoy": "convoy_sim.yaml", "Python Convoy": "convoy_py.yaml"}


def formation_times(scenario, seeds, duration_s):
    """Per seed: the formation time in seconds, or None when the convoy did not form."""
    times = []
    for seed in seeds:
        summary = rilbed.run(scenario, seed=seed, duration_s=duration_s, stop_when_formed=True)
        times.append(summary["formation_time_s"] if summary["formed"] else None)
    return times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds 1..N per controller")
    parser.add_argument("--duration-s", type=float, default=180.0, help="simulated seconds per run at most")
    parser.add_argument("--plot", default="convoy_over_seeds.png", help="the plot to write (PNG or SVG)")
    args = parser.parse_args()
    seeds = range(1, args.seeds + 1)
    results = {name: formation_times(os.path.join(SCENARIOS, f), seeds, args.duration_s) for name, f in CONTROLLERS.items()}

    print("| controller | seeds | formed | median formation time s | slowest s |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, times in results.items():
        formed = [t for t in times if t is not None]
        median = f"{statistics.median(formed):.1f}" if formed else "-"
        slowest = f"{max(formed):.1f}" if formed else "-"
        print(f"| {name} | {len(times)} | {len(formed)} | {median} | {slowest} |")

    fig, ax = plt.subplots(figsize=(7, 4))
    for offset, (name, times) in zip((-0.15, 0.15), results.items()):
        xs = [s + offset for s, t in zip(seeds, times) if t is not None]
        ys = [t for t in times if t is not None]
        ax.scatter(xs, ys, label=f"{name} ({len(ys)} of {len(times)} formed)")
    ax.set_xlabel("seed")
    ax.set_ylabel("formation time (s)")
    ax.set_title("Eight Kheperas forming a convoy (convoy_sim.yaml)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.plot)
    print(f"plot: {args.plot}")


if __name__ == "__main__":
    main()
