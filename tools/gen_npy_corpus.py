#!/usr/bin/python3
"""Writes tests/fuzz_corpus/npy: small .npy volumes written by numpy itself (Debian's
python3-numpy), which tests/test_io_npy.cpp reads and fuzz_npy starts from.

    /usr/bin/python3 tools/gen_npy_corpus.py     # from the repository root

Sample (x, y, z) holds (7 i) mod 251 with i = x + nx (y + ny z), less 100 for signed and float
types (bool: i odd), whatever the array's order: the files differ in how they store it.
"""
import os

import numpy as np

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "fuzz_corpus", "npy")
NX, NY, NZ = 5, 4, 3


def values(dtype):
    i = np.arange(NX * NY * NZ).reshape(NZ, NY, NX)  # [z, y, x]: x fastest
    if np.dtype(dtype) == np.bool_:
        return (i % 2 == 1)
    v = (i * 7) % 251
    if np.dtype(dtype).kind in "if":
        v = v - 100
    return v.astype(dtype)


def save(name, array, version=None):
    with open(os.path.join(OUT, name), "wb") as f:
        np.lib.format.write_array(f, array, version=version, allow_pickle=False)


def main():
    os.makedirs(OUT, exist_ok=True)
    save("f4_c.npy", values("<f4"))                                    # [z, y, x], C order
    save("f8_c.npy", values("<f8"))
    save("i2_big_c.npy", values(">i2"))                                # big-endian
    save("u2_fortran.npy", np.asfortranarray(values("<u2").T))         # [x, y, z], Fortran order
    save("u1_c.npy", values("|u1"))
    save("i1_c.npy", values("|i1"))
    save("u4_c.npy", values("<u4"))
    save("i4_big_c.npy", values(">i4"))
    save("bool_c.npy", values(np.bool_))
    save("f4_c_v2.npy", values("<f4"), version=(2, 0))                 # 4-byte header length
    save("f4_c_v3.npy", values("<f4"), version=(3, 0))
    save("f4_4d_c.npy", values("<f4")[np.newaxis])                     # (1, z, y, x)


if __name__ == "__main__":
    main()
