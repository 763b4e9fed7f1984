#!/usr/bin/env python3
"""Markdown tables of the fourteenth session's runs (bench/results/session14/run*), as in
bench/RESULTS.md: every cell gives the runs in order, `run1 / run2 / run3`.

    python3 bench/results/session14/summarise.py bench/results/session14/run1 run2 run3
"""
import re
import statistics
import sys
from collections import OrderedDict

runs = sys.argv[1:]
VOLUMES = [("sphere", "f32", "256"), ("sphere", "f32", "512"), ("sphere", "u8", "256"), ("sphere", "u8", "512"),
           ("gyroid", "f32", "256"), ("gyroid", "f32", "512"), ("gyroid", "u8", "256"), ("gyroid", "u8", "512")]


def rows(path):
    """voxmesh-bench table rows as dicts (header names as keys)."""
    out, header = [], None
    for line in open(path):
        parts = line.split()
        if parts[:2] == ["field", "type"]:
            header = parts
        elif header and len(parts) == len(header) and parts[0] in ("sphere", "gyroid", "ct", "blobs"):
            out.append(dict(zip(header, parts)))
    return out


def cell(values, fmt):
    return " / ".join(fmt % v if v is not None else "-" for v in values)


def peers():
    print("| volume | triangles | voxmesh | Flying Edges | FE 1 thr | FE / voxmesh | floor | voxmesh / floor |")
    print("|---|---|---|---|---|---|---|---|")
    per_run = []
    for run in runs:
        blocks, cur = [], None
        for line in open(f"{run}/peers.txt"):
            m = re.match(r"volume \S+: (\w+) (\d+)x", line)
            if m:
                cur = {"type": m.group(1), "size": m.group(2)}
                blocks.append(cur)
            elif line.startswith("voxmesh (cpu"):
                p = line.split()
                cur["vox"], cur["tri"] = float(p[5]), int(p[6])
            elif line.startswith("vtkFlyingEdges3D (1 thr)"):
                cur["fe1"] = float(line.split()[4])
            elif line.startswith("vtkFlyingEdges3D"):
                cur["fe"] = float(line.split()[2])
            elif line.startswith("streaming floor"):
                cur["floor"] = float(re.search(r"\): ([0-9.]+) s", line).group(1))
        per_run.append(blocks)
    names = ["sphere f32 256³", "sphere f32 512³", "gyroid f32 256³", "gyroid f32 512³", "sphere u8 256³",
             "sphere u8 512³", "gyroid u8 256³", "gyroid u8 512³", "ct i16 256³", "ct i16 512³"]
    for i, name in enumerate(names):
        b = [blocks[i] for blocks in per_run]
        print(f"| {name} | {b[0]['tri']:,} | {cell([x['vox'] for x in b], '%.4f')} | {cell([x['fe'] for x in b], '%.4f')} "
              f"| {cell([x['fe1'] for x in b], '%.4f')} | {cell([x['fe'] / x['vox'] for x in b], '%.2f×')} "
              f"| {cell([x['floor'] for x in b], '%.4f')} | {cell([x['vox'] / x['floor'] for x in b], '%.1f×')} |"
              .replace(",", " "))


def floor_runs():
    print("| run | call | f32 | u8 |")
    print("|---|---|---|---|")
    for run in runs:
        label = None
        got = OrderedDict()
        for line in open(f"{run}/floor_runs.txt"):
            if line.startswith("###"):
                label = line[4:].strip()
                got[label] = {}
            else:
                p = line.split()
                if len(p) > 12 and p[0] == "sphere":
                    got[label][p[1]] = (float(p[6]), float(p[12]))
        for label, by_type in got.items():
            print(f"| {run.rstrip('/').split('/')[-1]} | {label} | {by_type['f32'][0]:.4f} / {by_type['f32'][1]:.2f}× "
                  f"| {by_type['u8'][0]:.4f} / {by_type['u8'][1]:.2f}× |")


def backends():
    print("| volume | cpu | opencl | OpenCL / CPU |")
    print("|---|---|---|---|")
    data = [rows(f"{run}/backends.txt") for run in runs]
    for field, type_, size in VOLUMES:
        def get(d, backend):
            for r in d:
                if (r["field"], r["type"], r["size"]) == (field, type_, size) and r["backend"] == backend:
                    return float(r["median_s"])
            return None
        cpu = [get(d, "cpu") for d in data]
        ocl = [get(d, "opencl") for d in data]
        print(f"| {field} {type_} {size}³ | {cell(cpu, '%.4f')} | {cell(ocl, '%.4f')} "
              f"| {cell([c / o for c, o in zip(cpu, ocl)], '%.2f')} |")


def scaling(name):
    print("| volume | 1 thread (s) | 2: speed-up | 2: ceil | 2: fl_sp | 4 | 6 | 16 |")
    print("|---|---|---|---|---|---|---|---|")
    data = [rows(f"{run}/{name}") for run in runs]
    for field, type_, size in VOLUMES:
        def col(d, threads, key):
            for r in d:
                if (r["field"], r["type"], r["size"], r["thr"]) == (field, type_, size, str(threads)):
                    return float(r[key])
            return None
        print(f"| {field} {type_} {size}³ | {cell([col(d, 1, 'median_s') for d in data], '%.4f')} "
              f"| {cell([col(d, 2, 'speed') for d in data], '%.2f×')} | {cell([col(d, 2, 'ceil') for d in data], '%.2f')} "
              f"| {cell([col(d, 2, 'fl_sp') for d in data], '%.2f')} | "
              + " | ".join(cell([col(d, t, 'speed') for d in data], '%.2f×') for t in (4, 6, 16)) + " |")


def steady():
    print("| volume | 1 thread | 2 threads | speed-up (median of the rounds' ratios) |")
    print("|---|---|---|---|")
    per_run = []
    for run in runs:
        got = {}
        for line in open(f"{run}/scaling_steady.txt"):
            p = line.split()
            key = (p[0], p[1], p[2])
            rnd = int(p[-1])
            got.setdefault(key, {}).setdefault(rnd, {})[int(p[5])] = float(p[6])
        per_run.append(got)
    for field, type_, size in VOLUMES:
        key = (field, type_, size)
        one = [statistics.median(r[1] for r in g[key].values()) for g in per_run]
        two = [statistics.median(r[2] for r in g[key].values()) for g in per_run]
        ratio = [statistics.median(r[1] / r[2] for r in g[key].values()) for g in per_run]
        print(f"| {field} {type_} {size}³ | {cell(one, '%.4f')} | {cell(two, '%.4f')} | {cell(ratio, '%.2f×')} |")


for title, fn in [("peers", peers), ("floor_runs", floor_runs), ("backends", backends),
                  ("scaling (extract)", lambda: scaling("scaling.txt")),
                  ("scaling (extract_into)", lambda: scaling("scaling_into.txt")), ("scaling_steady", steady)]:
    print(f"\n#### {title}\n")
    fn()
