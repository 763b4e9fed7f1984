#!/usr/bin/python3
"""Plots voxmesh-bench --json output as PNGs.

    voxmesh-bench --paper --repeat 5 --json > paper.jsonl
    /usr/bin/python3 bench/plot.py paper.jsonl --out bench/plots

Writes, per (field, type):
  <field>_<type>_time.png      time vs threads, one line per size (CPU engine)
  <field>_<type>_speedup.png   speedup vs threads against ideal (capped at the core count)
  <field>_<type>_backends.png  CPU vs OpenCL vs hybrid, Mvoxels/s per size (when measured)
Uses Debian's python3-matplotlib: run with /usr/bin/python3.
"""

import argparse
import collections
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(paths):
    rows = []
    for p in paths:
        with (sys.stdin if p == "-" else open(p)) as f:
            for line in f:
                line = line.strip()
                if line.startswith("{"):
                    rows.append(json.loads(line))
    return [r for r in rows if r.get("status") == "ok"]


def set_thread_axis(ax, rows):
    ax.set_xscale("log", base=2)
    ticks = sorted({r["threads"] for r in rows})
    ax.set_xticks(ticks)
    ax.set_xticklabels([str(t) for t in ticks])
    ax.minorticks_off()


def plot_time(rows, title, path):
    fig, ax = plt.subplots(figsize=(6, 4), dpi=90)
    by_size = collections.defaultdict(list)
    for r in rows:
        if r["backend"] == "cpu":
            by_size[r["size"]].append(r)
    for size in sorted(by_size):
        pts = sorted(by_size[size], key=lambda r: r["threads"])
        ax.errorbar([r["threads"] for r in pts], [r["median_s"] for r in pts],
                    yerr=[[r["median_s"] - r["min_s"] for r in pts], [r["max_s"] - r["median_s"] for r in pts]],
                    marker="o", capsize=3, label=f"{size}³")
    set_thread_axis(ax, rows)
    ax.set_yscale("log")
    ax.set_xlabel("threads")
    ax.set_ylabel("seconds (median, min-max bars)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_speedup(rows, title, path, cores):
    fig, ax = plt.subplots(figsize=(6, 4), dpi=90)
    by_size = collections.defaultdict(list)
    for r in rows:
        if r["backend"] == "cpu" and r.get("speedup"):
            by_size[r["size"]].append(r)
    threads = sorted({r["threads"] for s in by_size.values() for r in s})
    for size in sorted(by_size):
        pts = sorted(by_size[size], key=lambda r: r["threads"])
        ax.plot([r["threads"] for r in pts], [r["speedup"] for r in pts], marker="o", label=f"{size}³")
    if threads:
        ax.plot(threads, [min(t, cores) for t in threads], "k--", label=f"ideal ({cores} cores)")
    set_thread_axis(ax, rows)
    ax.set_xlabel("threads")
    ax.set_ylabel("speedup vs 1 thread")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_backends(rows, title, path):
    # Best configuration per (backend, size): the fastest thread count.
    best = {}
    for r in rows:
        key = (r["backend"] if r["backend_ran"] == r["backend"] else f"{r['backend']}→{r['backend_ran']}", r["size"])
        if key not in best or r["median_s"] < best[key]["median_s"]:
            best[key] = r
    backends = sorted({k[0] for k in best})
    sizes = sorted({k[1] for k in best})
    if len(backends) < 2:
        return False
    fig, ax = plt.subplots(figsize=(6, 4), dpi=90)
    width = 0.8 / len(backends)
    for i, b in enumerate(backends):
        xs = [j + i * width for j, s in enumerate(sizes) if (b, s) in best]
        ys = [best[(b, s)]["mvox_s"] for s in sizes if (b, s) in best]
        ax.bar(xs, ys, width, label=b)
    ax.set_xticks([j + 0.4 - width / 2 for j in range(len(sizes))])
    ax.set_xticklabels([f"{s}³" for s in sizes])
    ax.set_ylabel("Mvoxels/s (best thread count, median)")
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json", nargs="+", help="voxmesh-bench --json output files ('-' for stdin)")
    ap.add_argument("--out", default=".", help="output folder")
    ap.add_argument("--prefix", default="", help="prefix of the PNG names")
    ap.add_argument("--cores", type=int, default=os.cpu_count(), help="cores for the ideal speedup line")
    args = ap.parse_args()
    rows = load(args.json)
    if not rows:
        sys.exit("no successful results in the input")
    os.makedirs(args.out, exist_ok=True)
    groups = collections.defaultdict(list)
    for r in rows:
        groups[(os.path.basename(r["field"]), r["type"])].append(r)
    for (field, typ), g in sorted(groups.items()):
        stem = os.path.join(args.out, args.prefix + f"{field}_{typ}".replace(".", "_"))
        plot_time(g, f"voxmesh CPU engine: {field} {typ}", stem + "_time.png")
        plot_speedup(g, f"voxmesh speedup: {field} {typ}", stem + "_speedup.png", args.cores)
        made = plot_backends(g, f"CPU vs OpenCL vs hybrid: {field} {typ}", stem + "_backends.png")
        print(f"wrote {stem}_time.png, {stem}_speedup.png" + (f", {stem}_backends.png" if made else ""))


if __name__ == "__main__":
    main()
