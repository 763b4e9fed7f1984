#!/usr/bin/python3
"""Times VTK's vtkFlyingEdges3D and vtkMarchingCubes and scikit-image's marching_cubes on one
volume file, beside voxmesh (voxmesh-bench on the same file, and the voxmesh Python package on
the same array in this process), and prints times, triangle counts and ratios. File loading is
never timed. Triangle counts must agree with VTK's.

    voxmesh-bench --field sphere --sizes 512 --write-volume /tmp/sphere512.nrrd
    /usr/bin/python3 bench/peers/peers.py /tmp/sphere512.nrrd --threads 2 --repeat 3

Needs Debian's python3-vtk9, python3-skimage and python3-numpy: run it with /usr/bin/python3
(a pyenv `python3` on PATH does not have them).
"""

import argparse
import glob
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

NRRD_TYPES = {
    "uint8": np.uint8, "uchar": np.uint8, "unsigned char": np.uint8, "uint8_t": np.uint8,
    "int8": np.int8, "signed char": np.int8, "int8_t": np.int8,
    "uint16": np.uint16, "ushort": np.uint16, "unsigned short": np.uint16, "uint16_t": np.uint16,
    "int16": np.int16, "short": np.int16, "int16_t": np.int16,
    "uint32": np.uint32, "uint": np.uint32, "unsigned int": np.uint32, "uint32_t": np.uint32,
    "int32": np.int32, "int": np.int32, "int32_t": np.int32,
    "float": np.float32, "double": np.float64,
}


def read_nrrd(path):
    """A raw-encoded 3-D NRRD: (array shaped (nz, ny, nx), iso from voxmesh_iso or None)."""
    with open(path, "rb") as f:
        magic = f.readline()
        if not magic.startswith(b"NRRD"):
            sys.exit(f"{path}: not a NRRD file")
        fields, keys = {}, {}
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"{path}: header without a blank line")
            line = line.decode("latin-1").rstrip("\r\n")
            if line == "":
                break
            if line.startswith("#"):
                continue
            if ":=" in line:
                k, v = line.split(":=", 1)
                keys[k.strip()] = v.strip()
            elif ":" in line:
                k, v = line.split(":", 1)
                fields[k.strip().lower()] = v.strip()
        offset = f.tell()
    if fields.get("encoding", "raw") != "raw":
        sys.exit(f"{path}: only raw NRRD encoding is supported here")
    if fields.get("dimension") != "3":
        sys.exit(f"{path}: need a 3-D volume")
    dtype = np.dtype(NRRD_TYPES[fields["type"].lower()])
    if dtype.itemsize > 1:
        dtype = dtype.newbyteorder(">" if fields.get("endian", "little") == "big" else "<")
    nx, ny, nz = (int(s) for s in fields["sizes"].split())
    data = np.fromfile(path, dtype=dtype, offset=offset)
    if data.size != nx * ny * nz:
        sys.exit(f"{path}: {data.size} samples, header says {nx}x{ny}x{nz}")
    data = data.astype(dtype.newbyteorder("="), copy=False).reshape(nz, ny, nx)
    iso = float(keys["voxmesh_iso"]) if "voxmesh_iso" in keys else None
    return np.ascontiguousarray(data), iso


def time_runs(fn, repeat, warmup=1):
    for _ in range(warmup):
        fn()
    times, result = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return times, result


def vtk_peers(vol, iso, threads, repeat, backend, normals, which):
    import vtk
    from vtkmodules.util import numpy_support

    smp = vtk.vtkSMPTools
    if backend and not smp.SetBackend(backend):
        print(f"warning: VTK SMP backend {backend} not available", file=sys.stderr)
    smp.Initialize(threads)
    info = {"vtk": vtk.vtkVersion.GetVTKVersion(), "smp_backend": smp.GetBackend(),
            "smp_threads": smp.GetEstimatedNumberOfThreads()}

    nz, ny, nx = vol.shape
    image = vtk.vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(1, 1, 1)
    image.SetOrigin(0, 0, 0)
    scalars = numpy_support.numpy_to_vtk(vol.ravel(), deep=False)  # zero-copy view of vol
    scalars.SetName("scalars")
    image.GetPointData().SetScalars(scalars)

    out = []
    for name, cls in (("vtkFlyingEdges3D", vtk.vtkFlyingEdges3D), ("vtkMarchingCubes", vtk.vtkMarchingCubes)):
        if name not in which:
            continue
        f = cls()
        f.SetInputData(image)
        f.SetValue(0, iso)
        f.SetComputeNormals(1 if normals else 0)
        f.SetComputeGradients(0)
        f.SetComputeScalars(0)

        def run(f=f):
            f.Modified()
            f.Update()
            o = f.GetOutput()
            return o.GetNumberOfPolys(), o.GetNumberOfPoints()

        times, (tris, verts) = time_runs(run, repeat)
        note = f"SMP {info['smp_backend']}, {info['smp_threads']} threads"
        if name == "vtkMarchingCubes":
            note = "serial (vtkMarchingCubes does not use vtkSMPTools)"
        out.append({"tool": name, "times": times, "triangles": tris, "vertices": verts, "note": note})
        f.SetInputData(None)
        del f
    return out, info


def skimage_peer(vol, iso, repeat, mask=None):
    from skimage import measure

    def run():
        verts, faces, _n, _v = measure.marching_cubes(vol, level=iso, mask=mask)
        return len(faces), len(verts)

    times, (tris, verts) = time_runs(run, repeat)
    return {"tool": "skimage.marching_cubes", "times": times, "triangles": tris, "vertices": verts,
            "note": "lewiner method, 1 thread; resolves ambiguous cases differently" + mask_note(mask)}


def x_mask(vol, fraction):
    """skimage's `mask` keeping the cells whose x lies in the first `fraction` of the volume
    (a cell by its far corner, as skimage looks), or None for no mask."""
    if fraction is None:
        return None
    mask = np.zeros(vol.shape, dtype=bool)
    mask[:, :, :int(round(fraction * vol.shape[2]))] = True
    return mask


def mask_note(mask):
    return "" if mask is None else f"; mask: x < {int(mask[0, 0].sum())}"


def import_voxmesh(bench):
    """The voxmesh Python package: importable as it is, else the one of voxmesh-bench's build,
    else the newest build's; None where there is none."""
    try:
        import voxmesh
    except ImportError:
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        builds = sorted(glob.glob(os.path.join(root, "build*")), key=os.path.getmtime, reverse=True)
        if bench:
            builds.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(bench))))
        found = [b for b in builds if glob.glob(os.path.join(b, "src", "capi", "libvoxmesh_c.so*"))
                 and os.path.exists(os.path.join(b, "python", "voxmesh", "_library.py"))]
        if not found:
            print("the voxmesh Python package was not found: build with VOXMESH_BUILD_C_API or set PYTHONPATH",
                  file=sys.stderr)
            return None
        sys.path.insert(0, os.path.join(found[0], "python"))
        import voxmesh
    return voxmesh


def voxmesh_python_peer(vol, iso, threads, repeat, normals, bench):
    """voxmesh through its Python package on the same array, in this process (as skimage)."""
    voxmesh = import_voxmesh(bench)
    if voxmesh is None:
        return None

    def run():
        mesh = voxmesh.extract(vol, iso=iso, backend="cpu", threads=threads, normals=normals)
        return mesh.triangle_count, mesh.vertex_count

    times, (tris, verts) = time_runs(run, repeat)
    return {"tool": f"voxmesh (python, {threads} thr)", "times": times, "triangles": tris, "vertices": verts,
            "note": "voxmesh.extract on the numpy array, this process"}


def voxmesh_marching_cubes_peer(vol, iso, threads, repeat, bench, mask=None):
    """voxmesh.marching_cubes, the drop-in for skimage's: the same four arrays (verts in array
    axis order, int32 faces, normals, values), so the same work for the caller as skimage."""
    voxmesh = import_voxmesh(bench)
    if voxmesh is None:
        return None

    def run():
        verts, faces, _n, _v = voxmesh.marching_cubes(vol, level=iso, threads=threads, backend="cpu", mask=mask)
        return len(faces), len(verts)

    times, (tris, verts) = time_runs(run, repeat)
    return {"tool": f"voxmesh.marching_cubes ({threads} thr)", "times": times, "triangles": tris,
            "vertices": verts, "note": "skimage's arguments and results, this process" + mask_note(mask)}


def find_bench(explicit):
    if explicit:
        return explicit
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    found = sorted(glob.glob(os.path.join(root, "build*", "bench", "voxmesh-bench")), key=os.path.getmtime)
    if found:
        return found[-1]
    return shutil.which("voxmesh-bench")


def voxmesh_run(bench, path, iso, threads, repeat, normals):
    cmd = [bench, "--input", path, "--iso", repr(iso), "--threads", str(threads), "--repeat", str(repeat),
           "--warmup", "1", "--json", "--quiet"]
    if not normals:
        cmd.append("--no-normals")
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        print(f"voxmesh-bench failed ({' '.join(cmd)}):\n{proc.stderr}", file=sys.stderr)
        return None, cmd
    rows = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    ok = [r for r in rows if r["status"] == "ok"]
    if not ok:
        print(f"voxmesh-bench gave no result: {proc.stdout}", file=sys.stderr)
        return None, cmd
    r = ok[0]
    return {"tool": f"voxmesh (cpu, {r['threads']} thr)", "times": r["times_s"], "triangles": r["triangles"],
            "vertices": r["vertices"], "floor_s": r["floor_s"], "note": "voxmesh-bench, end-to-end extract()"}, cmd


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("volume", help="raw NRRD (e.g. from voxmesh-bench --write-volume)")
    ap.add_argument("--iso", type=float, help="iso value (default: voxmesh_iso from the file)")
    ap.add_argument("--threads", type=int, default=os.cpu_count(), help="threads for VTK and voxmesh")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per tool (after one warmup)")
    ap.add_argument("--vtk-backend", default="", help="vtkSMPTools backend (TBB, STDThread, Sequential)")
    ap.add_argument("--bench", help="path to voxmesh-bench (default: newest build*/bench/voxmesh-bench)")
    ap.add_argument("--tools", default="voxmesh,py,fe,mc,skimage",
                    help="comma list of voxmesh (voxmesh-bench), py (the voxmesh Python package), pymc "
                         "(voxmesh.marching_cubes, skimage's drop-in), fe, mc, skimage")
    ap.add_argument("--no-normals", action="store_true", help="every tool without normals")
    ap.add_argument("--fe-scaling", action="store_true", help="also time Flying Edges on 1 thread")
    ap.add_argument("--json", action="store_true", help="one JSON object per tool")
    ap.add_argument("--mask-x", type=float, metavar="FRACTION",
                    help="pass skimage's `mask` to skimage and pymc, keeping the cells in the first FRACTION of x "
                         "(the other tools mesh everything)")
    args = ap.parse_args()
    known = {"voxmesh", "py", "pymc", "fe", "mc", "skimage"}
    tools = set(t for t in args.tools.split(",") if t)
    if not tools or not tools <= known:
        ap.error(f"--tools: unknown {sorted(tools - known) or 'empty list'}; choose from {','.join(sorted(known))}")
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    if args.threads < 1:
        ap.error("--threads must be at least 1")
    if args.iso is not None and not math.isfinite(args.iso):
        ap.error("--iso must be a finite number")
    normals = not args.no_normals

    vol, file_iso = read_nrrd(args.volume)
    iso = args.iso if args.iso is not None else file_iso
    if iso is None:
        sys.exit("no iso: give --iso (the file has no voxmesh_iso)")
    if np.issubdtype(vol.dtype, np.integer) and float(iso).is_integer():
        print(f"warning: integer data with integer iso {iso}: samples equal to it make tools disagree; "
              "use a half-integer iso", file=sys.stderr)
    nz, ny, nx = vol.shape
    results = []
    failed = False  # a tool asked for that gave no result: the exit status says so

    if "voxmesh" in tools:
        bench = find_bench(args.bench)
        if not bench:
            print("voxmesh-bench not found: build it or pass --bench", file=sys.stderr)
            failed = True
        else:
            r, cmd = voxmesh_run(bench, os.path.abspath(args.volume), iso, args.threads, args.repeat, normals)
            if r:
                r["command"] = " ".join(cmd)
                results.append(r)
            else:
                failed = True
    which = {n for k, n in (("fe", "vtkFlyingEdges3D"), ("mc", "vtkMarchingCubes")) if k in tools}
    vtk_info = {}
    if which:
        vres, vtk_info = vtk_peers(vol, iso, args.threads, args.repeat, args.vtk_backend, normals, which)
        results += vres
        if args.fe_scaling and "vtkFlyingEdges3D" in which:
            one, _ = vtk_peers(vol, iso, 1, args.repeat, args.vtk_backend, normals, {"vtkFlyingEdges3D"})
            one[0]["tool"] = "vtkFlyingEdges3D (1 thr)"
            results += one
            import vtk
            vtk.vtkSMPTools.Initialize(args.threads)
    if "py" in tools:
        r = voxmesh_python_peer(vol, iso, args.threads, args.repeat, normals, find_bench(args.bench))
        if r:
            results.append(r)
    if "pymc" in tools:
        r = voxmesh_marching_cubes_peer(vol, iso, args.threads, args.repeat, find_bench(args.bench),
                                        x_mask(vol, args.mask_x))
        if r:
            results.append(r)
    if "skimage" in tools:
        results.append(skimage_peer(vol, iso, args.repeat, x_mask(vol, args.mask_x)))

    for r in results:
        r["best_s"] = min(r["times"])
        r["median_s"] = statistics.median(r["times"])
    base = next((r for r in results if r["tool"].startswith("voxmesh")), None)

    if args.json:
        for r in results:
            row = dict(r, volume=args.volume, dtype=str(vol.dtype), dims=[nx, ny, nz], iso=iso, threads=args.threads)
            if base:
                row["ratio_vs_voxmesh"] = r["median_s"] / base["median_s"]
            row.update(vtk_info)
            print(json.dumps(row))
    else:
        print(f"volume {args.volume}: {vol.dtype} {nx}x{ny}x{nz}, iso {iso!r}, threads {args.threads}, "
              f"normals {'on' if normals else 'off'}, best/median of {args.repeat} after 1 warmup, loading excluded")
        if vtk_info:
            print(f"VTK {vtk_info['vtk']}: vtkSMPTools backend {vtk_info['smp_backend']}, "
                  f"{vtk_info['smp_threads']} threads")
        print(f"{'tool':28} {'best_s':>9} {'median_s':>9} {'triangles':>10} {'vertices':>10} {'median/voxmesh':>15}  note")
        for r in results:
            ratio = f"{r['median_s'] / base['median_s']:.2f}x" if base else "-"
            print(f"{r['tool']:28} {r['best_s']:9.4f} {r['median_s']:9.4f} {r['triangles']:10d} {r['vertices']:10d} "
                  f"{ratio:>15}  {r['note']}")
        if base and base.get("floor_s"):
            print(f"streaming floor (one threaded read of the volume, voxmesh-bench): {base['floor_s']:.4f} s; "
                  f"voxmesh median is {base['median_s'] / base['floor_s']:.2f}x it")
        if base and "command" in base:
            print(f"voxmesh command: {base['command']}")

    # Triangle counts: voxmesh's classic table gives VTK's triangles exactly.
    status = 0
    if base:
        for r in results:
            if r["tool"].startswith("vtk") or r["tool"].startswith("voxmesh (python"):
                if r["triangles"] != base["triangles"]:
                    print(f"MISMATCH: voxmesh {base['triangles']} triangles vs {r['tool']} {r['triangles']} "
                          f"(iso {iso!r})", file=sys.stdout if not args.json else sys.stderr)
                    status = 1
                elif not args.json:
                    print(f"triangle count agrees with {r['tool']}: {r['triangles']}")
    return 1 if failed else status


if __name__ == "__main__":
    sys.exit(main())
