#!/usr/bin/env python3
"""Hybrid's choice of mode (src/cl/hybrid_schedule.hpp, rewritten here) on made-up times: three
volumes of one shape meshed 8 calls each in turn (a warm-up and 7 timed, as voxmesh-bench
--warmup 1 --repeat 7), each call's time the mode's time times lognormal noise. Prints, per
volume, the median over trials and the 10th percentile of (the quicker of CPU alone and device
alone) / (median of the 7 timed calls), without and with the data-change rechecks.

usage: simulate_modes.py [DATA_CHANGE (2)] [NOISE_SIGMA (0.15)] [TRIALS (2000)]
The times (ms) are the H200's 16-thread u8 512³ runs with --reuse-mesh (07_final_*_reuse_mesh):
the split, the CPU engine alone, the device alone."""
import math
import random
import statistics
import sys

MIN_RECHECK, MAX_RECHECK, RECHECK_COST = 4, 256, 0.01
VOLUMES = [("sphere", (12, 11, 9)), ("gyroid", (30, 27, 14)), ("ct", (11, 10, 8))]


def recheck_calls(gap):
    calls = math.ceil(max(0.0, gap) / RECHECK_COST)
    return MAX_RECHECK if calls >= MAX_RECHECK else max(MIN_RECHECK, calls)


class Modes:
    def __init__(self):
        self.seconds, self.measured_at, self.stale = [0.0] * 3, [0] * 3, [False] * 3
        self.calls = self.split_calls = 0

    def choose(self):
        if self.split_calls == 0:
            return 0
        for m in range(3):
            if self.seconds[m] <= 0:
                return m
        best = min(range(3), key=lambda m: self.seconds[m])
        pick = best
        for m in range(3):
            if m == best:
                continue
            due = self.stale[m] or self.calls - self.measured_at[m] >= recheck_calls(self.seconds[m] / self.seconds[best] - 1)
            if due and (pick == best or self.seconds[m] < self.seconds[pick]):
                pick = m
        return pick

    def record(self, m, s, data_change):
        if m == 0:
            self.split_calls += 1
            if self.split_calls == 1:
                return
        before = self.seconds[m]
        quickest = before > 0 and all(0 < self.seconds[o] and before <= self.seconds[o] for o in range(3) if o != m)
        self.seconds[m], self.measured_at[m], self.stale[m] = s, self.calls, False
        self.calls += 1
        if not quickest:
            return
        change = s / before
        for o in range(3):
            if o != m:
                self.seconds[o] *= change
                if data_change and (change > data_change or change * data_change < 1) and self.seconds[o] <= 2 * s:
                    self.stale[o] = True


def main():
    data_change = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
    sigma = float(sys.argv[2]) if len(sys.argv) > 2 else 0.15
    trials = int(sys.argv[3]) if len(sys.argv) > 3 else 2000
    random.seed(1)
    for label, change in (("without data-change rechecks", 0), (f"with them (x{data_change})", data_change)):
        ratios = {name: [] for name, _ in VOLUMES}
        for _ in range(trials):
            modes = Modes()
            for name, times in VOLUMES:
                timed = []
                for call in range(8):
                    m = modes.choose()
                    s = times[m] * math.exp(random.gauss(0, sigma))
                    modes.record(m, s, change)
                    if call > 0:
                        timed.append(s)
                ratios[name].append(min(times[1], times[2]) / statistics.median(timed))
        print(label + ": " + ", ".join(f"{n} median {statistics.median(r):.3f} p10 {sorted(r)[len(r) // 10]:.3f}"
                                       for n, r in ratios.items()))


if __name__ == "__main__":
    main()
