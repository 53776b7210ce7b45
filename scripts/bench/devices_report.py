#!/usr/bin/env python3
"""Writes docs/devices.md and its bar plot from the `pathcl bench --json` files in a directory.

Usage: devices_report.py RESULTS_DIR OUT.md OUT.png
Rows are grouped by device (or device set) and suite; a group's score is the median over its runs, with
the spread (max - min) / median. A device that failed the gate is listed as FAILED, with no score.
"""
import json
import os
import statistics
import sys


def load(directory):
    runs = []
    for name in sorted(os.listdir(directory)):
        if name.endswith(".json"):
            with open(os.path.join(directory, name)) as f:
                runs.append((name, json.load(f)))
    return runs


def groups(runs):
    table = {}
    for name, run in runs:
        suite = "%s v%d" % (run["suite"]["name"], run["suite"]["version"])
        for r in run["results"]:
            key = (" + ".join(r["devices"]), r["platform"], suite)
            table.setdefault(key, []).append((name, run, r))
    return table


def spread(values):
    m = statistics.median(values)
    return (max(values) - min(values)) / m if m > 0 else 0


def main():
    directory, out_md, out_png = sys.argv[1:4]
    table = groups(load(directory))
    lines = ["# Devices", "",
             "`pathcl bench` results (`scripts/bench/devices`; the JSON files are in `bench/results/devices/`).",
             "A score counts only when the device passes the correctness gate: every scene's image within its",
             "z-tests against the shipped reference and the analytic scenes within 4 standard errors. Scores are",
             "geometric means over the suite's scenes, medians over the runs; the spread is (max - min) / median.",
             "", "| device | platform | suite | runs | gate | same bits as PoCL | Msamples/s | spread | 1 / s to relMSE 1e-2 | spread |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    bars = []
    for (device, platform, suite), rows in sorted(table.items()):
        passed = all(r["verdict"] == "PASSED" for _, _, r in rows)
        same = all(r["same_bits_as_pocl"] for _, _, r in rows)
        if passed:
            samples = [r["score"]["msamples_per_second"] for _, _, r in rows]
            conv = [r["score"]["per_second_to_relmse_1e-2"] for _, _, r in rows]
            lines.append("| %s | %s | %s | %d | passed | %s | %.3f | %.1f %% | %.3f | %.1f %% |" % (
                device, platform, suite, len(rows), "yes" if same else "no", statistics.median(samples),
                100 * spread(samples), statistics.median(conv), 100 * spread(conv)))
            bars.append(("%s\n%s" % (device, suite), statistics.median(samples), statistics.median(conv)))
        else:
            failures = sorted({f for _, _, r in rows for f in r["failures"]})
            lines.append("| %s | %s | %s | %d | FAILED: %s | %s | – | | – | |" % (
                device, platform, suite, len(rows), "; ".join(failures), "yes" if same else "no"))
    lines += ["", "![scores](img/devices.png)", ""]
    with open(out_md, "w") as f:
        f.write("\n".join(lines))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 0.6 * len(bars) + 1.5))
    names = [b[0] for b in bars]
    for ax, index, title in ((axes[0], 1, "Msamples/s"), (axes[1], 2, "1 / s to relMSE 1e-2")):
        ax.barh(names, [b[index] for b in bars])
        ax.set_title(title)
    axes[1].set_yticks([])
    fig.tight_layout()
    fig.savefig(out_png, dpi=100)


if __name__ == "__main__":
    main()
