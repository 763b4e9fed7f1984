#!/usr/bin/env python3
"""Hybrid against the faster of the CPU engine and OpenCL alone, from voxmesh-bench --save files
(--backends cpu,opencl,hybrid --threads 2,N): one markdown table per file, medians in ms.

usage: summarise.py FILE.jsonl [FILE.jsonl ...]
OpenCL alone runs its host work on all cores whatever --threads says, so one OpenCL column
serves both thread counts. cpu share: the median share of samples Hybrid's CPU side meshed
(1: the CPU engine alone ran, 0: the device alone, between: the split)."""
import json
import math
import sys
from collections import defaultdict


def main(paths):
    for path in paths:
        rows = [json.loads(line) for line in open(path)]
        by_volume = defaultdict(dict)
        for r in rows:
            if r["status"] == "ok":
                by_volume[(r["field"], r["type"], r["size"])][(r["backend"], r["threads"])] = r
        counts = sorted({t for v in by_volume.values() for (b, t) in v if b == "hybrid"})
        print(f"\n{path}\n")
        head = "| volume | OpenCL |" + "".join(f" CPU {t} | Hybrid {t} (cpu share) | ratio {t} |" for t in counts)
        print(head)
        print("|" + "---|" * (2 + 3 * len(counts)))
        ratios = defaultdict(list)
        for (field, type_, size), v in by_volume.items():
            cl = next(r["median_s"] for (b, _), r in v.items() if b == "opencl")
            line = f"| {field} {type_} {size}³ | {cl * 1e3:.1f} |"
            for t in counts:
                cpu, hyb = v[("cpu", t)]["median_s"], v[("hybrid", t)]
                ratio = min(cpu, cl) / hyb["median_s"]
                ratios[t].append(ratio)
                line += f" {cpu * 1e3:.1f} | {hyb['median_s'] * 1e3:.1f} ({hyb['cpu_share']:.2f}) | {ratio:.2f} |"
            print(line)
        print()
        for t in counts:
            r = ratios[t]
            geo = math.exp(sum(map(math.log, r)) / len(r))
            print(f"- {t} threads: ratio {min(r):.2f}–{max(r):.2f}, geometric mean {geo:.2f}, "
                  f"{sum(x >= 0.95 for x in r)} of {len(r)} at ≥ 0.95")


if __name__ == "__main__":
    main(sys.argv[1:])
