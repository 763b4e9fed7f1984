#!/usr/bin/python3
"""Times the scikit-image drop-in's cut of a volume to its mask's kept cells
(voxmesh._skimage._crop_to_mask, the mask's box found and the kept part of the mask copied) on
512³ masks as marching_cubes(step_size=1) hands them over (the mask[1:, 1:, 1:] view): half the
volume kept along the first axis, half along the last, and a centred box. Median of 7 calls.

    PYTHONPATH=build/python /usr/bin/python3 bench/peers/mask_crop.py
"""

import statistics
import time

import numpy as np
from voxmesh._skimage import _crop_to_mask


def main():
    n = 512
    data = np.zeros((n, n, n), np.float32)
    first = np.zeros((n, n, n), bool)
    first[:n // 2] = True
    last = np.ascontiguousarray(first.transpose(2, 1, 0))
    box = np.zeros((n, n, n), bool)
    box[200:300, 150:300, 100:400] = True
    for name, mask in (("half, first axis", first), ("half, last axis", last), ("centred box", box)):
        times = []
        for _ in range(7):
            t0 = time.perf_counter()
            _, _, corner = _crop_to_mask(data[1:, 1:, 1:], mask[1:, 1:, 1:])
            times.append(time.perf_counter() - t0)
        print(f"{name:17} median {statistics.median(times) * 1e3:5.1f} ms  corner {tuple(corner)}")


if __name__ == "__main__":
    main()
