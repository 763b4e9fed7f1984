#!/usr/bin/env python3
"""Tables of pause_ab.sh's output: bench/results/session19/summarise_pause.py DIR"""
import json
import sys
from collections import defaultdict
from pathlib import Path

d = Path(sys.argv[1])


def rows(name):
    p = d / name
    return [json.loads(line) for line in p.read_text().splitlines() if line.strip()] if p.exists() else []


print("| volume | pause | before: 1 thr / 2 thr (s) | before: speed-up | after: 1 thr / 2 thr (s) | after: speed-up |")
print("|---|---|---|---|---|---|")
for pause in (0, 10):
    # build -> (field, type, size) -> threads -> [median_s of each run]
    t = {b: defaultdict(lambda: defaultdict(list)) for b in ("old", "new")}
    for b in ("old", "new"):
        for r in rows(f"scaling_pause{pause}_{b}.jsonl"):
            t[b][(r["field"], r["type"], r["size"])][r["threads"]].append(r["median_s"])
    for key in t["old"]:
        cells = []
        for b in ("old", "new"):
            one, two = t[b][key][1], t[b][key][2]
            times = " · ".join(f"{a:.4f} / {c:.4f}" for a, c in zip(one, two))
            speed = " · ".join(f"{a / c:.2f}×" for a, c in zip(one, two))
            cells += [times, speed]
        print(f"| {key[0]} {key[1]} {key[2]}³ | {pause} ms | " + " | ".join(cells) + " |")

print()
print("| sculpt | pause | before: update p50 / p95 (ms) | after: update p50 / p95 (ms) |")
print("|---|---|---|---|")
for pause in (0, 16):
    s = {b: defaultdict(list) for b in ("old", "new")}
    for b in ("old", "new"):
        for r in rows(f"sculpt_pause{pause}_{b}.jsonl"):
            s[b][r["size"]].append(f'{r["update_p50_ms"]:.3f} / {r["update_p95_ms"]:.3f}')
    for size in s["old"]:
        print(f"| {size}³, 2 threads | {pause} ms | " + " · ".join(s["old"][size]) + " | " + " · ".join(s["new"][size]) + " |")
