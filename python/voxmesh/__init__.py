"""voxmesh from Python: marching cubes on numpy volumes through the C API (libvoxmesh_c), with
ctypes and numpy only.

    import numpy as np, voxmesh
    z, y, x = np.mgrid[:128, :128, :128]
    volume = 40.0 - np.sqrt((x - 63.5) ** 2 + (y - 63.5) ** 2 + (z - 63.5) ** 2)
    mesh = voxmesh.extract(volume, iso=0.0)          # threads: every CPU this process may use
    mesh.positions, mesh.normals, mesh.indices        # (V, 3) float32, (V, 3) float32, (T, 3) uint32
    mesh.write("sphere.ply")

Models go the paper's way too: voxmesh.read_mesh("model.stl") (or Mesh.from_arrays(positions,
indices)), voxmesh.voxelize(model, resolution=128) to a signed-distance Volume, and extract
of that at iso 0 back in the model's units; mesh.topology() says whether a mesh is closed.
voxmesh.Sculpt(volume) edits a copy of a volume with brushes and re-meshes only the blocks an
edit reaches (the paper's real-time sculpting loop).

A volume is a 3-D array indexed [z, y, x] (C order, so x varies fastest, as voxmesh stores
samples); positions are x, y, z in that order: origin + index * spacing, with spacing and
origin given as (x, y, z). The mesh is the library's canonical mesh, the same buffers the C++
API gives. Its arrays are views of the library's memory, kept alive as long as any of them is.

The shared library is found through VOXMESH_LIBRARY (a path), else where the build or install
that made this package put it.
"""

import collections
import ctypes
import numbers
import operator
import os
import threading
import warnings

import numpy as np

__all__ = ["extract", "marching_cubes", "vertex_edges", "triangle_cells", "edge_cell_ranges", "value_range", "ValueRange", "read_volume", "read_raw", "write_nrrd", "read_mesh", "voxelize", "devices",
           "release_scratch_memory",
           "Mesh", "Volume", "Topology", "Sculpt", "Block", "UpdateResult", "StrokeFrame", "VoxmeshError", "VoxmeshMemoryError",
           "version"]

_DTYPES = [np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.float32, np.float64]
_BACKENDS = {"auto": 0, "cpu": 1, "opencl": 2, "hybrid": 3}
_BACKEND_NAMES = {code: name for name, code in _BACKENDS.items()}
_DEVICE_TYPES = {"any": 0, "cpu": 1, "gpu": 2, "accelerator": 3}
_DEVICE_TYPE_NAMES = {code: name for name, code in _DEVICE_TYPES.items()}


class VoxmeshError(Exception):
    """A call the library refused: the message names the problem."""


class VoxmeshMemoryError(VoxmeshError, MemoryError):
    """Memory ran out during the call."""


class _VolumeView(ctypes.Structure):
    _fields_ = [("data", ctypes.c_void_p), ("type", ctypes.c_int), ("dims", ctypes.c_size_t * 3),
                ("spacing", ctypes.c_double * 3), ("origin", ctypes.c_double * 3)]


class _Topology(ctypes.Structure):
    _fields_ = [("boundary_edges", ctypes.c_size_t), ("nonmanifold_edges", ctypes.c_size_t),
                ("euler", ctypes.c_longlong), ("components", ctypes.c_size_t)]


class _VoxelizeOptions(ctypes.Structure):
    _fields_ = [("resolution", ctypes.c_size_t), ("padding", ctypes.c_size_t), ("field", ctypes.c_int),
                ("band", ctypes.c_double), ("threads", ctypes.c_uint), ("fill", ctypes.c_int)]


class _Stats(ctypes.Structure):
    _fields_ = [("backend", ctypes.c_int), ("threads", ctypes.c_uint), ("workers", ctypes.c_uint),
                ("classify_s", ctypes.c_double), ("scan_s", ctypes.c_double), ("generate_s", ctypes.c_double),
                ("total_s", ctypes.c_double)]


class _Options(ctypes.Structure):
    _fields_ = [("iso", ctypes.c_double), ("backend", ctypes.c_int), ("threads", ctypes.c_uint),
                ("normals", ctypes.c_int), ("inside_below", ctypes.c_int), ("devices", ctypes.POINTER(ctypes.c_int)),
                ("device_count", ctypes.c_size_t), ("device_type", ctypes.c_int), ("chunk_planes", ctypes.c_size_t),
                ("memory_budget", ctypes.c_size_t)]


class _Device(ctypes.Structure):
    _fields_ = [("index", ctypes.c_int), ("type", ctypes.c_int), ("compute_units", ctypes.c_uint),
                ("global_memory", ctypes.c_uint64), ("max_allocation", ctypes.c_uint64), ("fp64", ctypes.c_int),
                ("host_memory", ctypes.c_int), ("platform", ctypes.c_char * 128), ("name", ctypes.c_char * 128),
                ("version", ctypes.c_char * 128)]


class _DeviceStats(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char * 128), ("chunks", ctypes.c_size_t), ("voxels", ctypes.c_size_t),
                ("kernel_s", ctypes.c_double), ("transfer_s", ctypes.c_double), ("wall_s", ctypes.c_double),
                ("setup_s", ctypes.c_double), ("programs_built", ctypes.c_size_t),
                ("chunks_handed_over", ctypes.c_size_t)]


class _RawLayout(ctypes.Structure):
    _fields_ = [("dims", ctypes.c_size_t * 3), ("type", ctypes.c_int), ("big_endian", ctypes.c_int),
                ("offset", ctypes.c_size_t), ("spacing", ctypes.c_double * 3), ("origin", ctypes.c_double * 3)]


class _ValueRange(ctypes.Structure):
    _fields_ = [("min", ctypes.c_double), ("max", ctypes.c_double), ("nonfinite", ctypes.c_uint64),
                ("first_nonfinite", ctypes.c_size_t * 3), ("equal", ctypes.c_uint64)]


class _VolumeInfo(ctypes.Structure):
    _fields_ = [("format", ctypes.c_char * 16), ("encoding", ctypes.c_char * 16), ("big_endian", ctypes.c_int),
                ("flipped", ctypes.c_int * 3), ("rotation_dropped", ctypes.c_int), ("value_scale", ctypes.c_double),
                ("value_offset", ctypes.c_double), ("directions", ctypes.c_double * 9),
                ("world_origin", ctypes.c_double * 3)]


class _SculptOptions(ctypes.Structure):
    _fields_ = [("iso", ctypes.c_double), ("threads", ctypes.c_uint), ("block_size", ctypes.c_size_t),
                ("normals", ctypes.c_int), ("inside_below", ctypes.c_int), ("strength_scale", ctypes.c_double),
                ("backend", ctypes.c_int), ("device", ctypes.c_int)]


class _UpdateResult(ctypes.Structure):
    _fields_ = [("changed", ctypes.POINTER(ctypes.c_size_t)), ("changed_count", ctypes.c_size_t),
                ("remeshed", ctypes.c_size_t), ("seconds", ctypes.c_double)]


class _Block(ctypes.Structure):
    _fields_ = [("index", ctypes.c_size_t), ("coord", ctypes.c_size_t * 3), ("cell_begin", ctypes.c_size_t * 3),
                ("cell_end", ctypes.c_size_t * 3), ("positions", ctypes.c_void_p), ("normals", ctypes.c_void_p),
                ("indices", ctypes.c_void_p), ("vertex_count", ctypes.c_size_t), ("triangle_count", ctypes.c_size_t)]


class _StrokeFrame(ctypes.Structure):
    _fields_ = [("frame", ctypes.c_size_t), ("line", ctypes.c_size_t), ("brush", ctypes.c_int), ("units", ctypes.c_int),
                ("center", ctypes.c_double * 3), ("radius", ctypes.c_double), ("strength", ctypes.c_double),
                ("edit_seconds", ctypes.c_double), ("update_seconds", ctypes.c_double),
                ("blocks_changed", ctypes.c_size_t), ("blocks_remeshed", ctypes.c_size_t)]


_STROKE_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(_StrokeFrame), ctypes.c_void_p)


def _library_path():
    given = os.environ.get("VOXMESH_LIBRARY")
    if given:
        return given
    from . import _library  # written by CMake beside this file

    return os.path.join(os.path.dirname(os.path.abspath(__file__)), _library.PATH)


def _expected_version():
    """The library version this package was built with (_library.VERSION, written by CMake or
    setup.py); None where the package does not know it."""
    try:
        from . import _library
    except ImportError:
        return None
    return getattr(_library, "VERSION", None)


def _load():
    path = _library_path()
    lib = ctypes.CDLL(path)
    lib.voxmesh_version.restype = ctypes.c_char_p
    lib.voxmesh_version.argtypes = []
    # Structs and calls are declared below for one version: another's may differ in layout.
    expected, found = _expected_version(), lib.voxmesh_version().decode()
    if expected is not None and found != expected:
        raise ImportError(f"voxmesh: the library {path} is version {found}, but this Python package is "
                          f"{expected}; install matching versions or point VOXMESH_LIBRARY at the right one")
    handle = ctypes.c_void_p
    lib.voxmesh_default_options.restype = _Options
    lib.voxmesh_default_options.argtypes = []
    lib.voxmesh_extract.restype = ctypes.c_int
    lib.voxmesh_extract.argtypes = [ctypes.POINTER(_VolumeView), ctypes.POINTER(_Options), ctypes.POINTER(handle)]
    for name in ("voxmesh_mesh_vertex_count", "voxmesh_mesh_triangle_count"):
        getattr(lib, name).restype = ctypes.c_size_t
        getattr(lib, name).argtypes = [handle]
    for name in ("voxmesh_mesh_positions", "voxmesh_mesh_normals", "voxmesh_mesh_indices"):
        getattr(lib, name).restype = ctypes.c_void_p
        getattr(lib, name).argtypes = [handle]
    lib.voxmesh_mesh_stats.restype = _Stats
    lib.voxmesh_mesh_stats.argtypes = [handle]
    lib.voxmesh_mesh_warnings.restype = ctypes.c_char_p
    lib.voxmesh_mesh_warnings.argtypes = [handle]
    lib.voxmesh_mesh_free.restype = None
    lib.voxmesh_mesh_free.argtypes = [handle]
    lib.voxmesh_write_mesh.restype = ctypes.c_int
    lib.voxmesh_write_mesh.argtypes = [ctypes.c_char_p, handle]
    lib.voxmesh_read_mesh.restype = ctypes.c_int
    lib.voxmesh_read_mesh.argtypes = [ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_mesh_from_arrays.restype = ctypes.c_int
    lib.voxmesh_mesh_from_arrays.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t,
                                             ctypes.POINTER(handle)]
    lib.voxmesh_analyze_topology.restype = ctypes.c_int
    lib.voxmesh_analyze_topology.argtypes = [handle, ctypes.POINTER(_Topology)]
    lib.voxmesh_default_voxelize_options.restype = _VoxelizeOptions
    lib.voxmesh_default_voxelize_options.argtypes = []
    lib.voxmesh_voxelize.restype = ctypes.c_int
    lib.voxmesh_voxelize.argtypes = [handle, ctypes.POINTER(_VoxelizeOptions), ctypes.POINTER(handle)]
    lib.voxmesh_read_volume.restype = ctypes.c_int
    lib.voxmesh_read_volume.argtypes = [ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_volume_get_view.restype = _VolumeView
    lib.voxmesh_volume_get_view.argtypes = [handle]
    lib.voxmesh_volume_free.restype = None
    lib.voxmesh_volume_free.argtypes = [handle]
    lib.voxmesh_device_count.restype = ctypes.c_size_t
    lib.voxmesh_device_count.argtypes = []
    lib.voxmesh_release_scratch_memory.restype = None
    lib.voxmesh_release_scratch_memory.argtypes = []
    lib.voxmesh_get_device.restype = ctypes.c_int
    lib.voxmesh_get_device.argtypes = [ctypes.c_size_t, ctypes.POINTER(_Device)]
    _declare_sculpt(lib, handle)
    _declare_io(lib, handle)
    lib.voxmesh_last_error.restype = ctypes.c_char_p
    lib.voxmesh_last_error.argtypes = []
    return lib


def _declare_io(lib, handle):
    status, size = ctypes.c_int, ctypes.c_size_t
    lib.voxmesh_mesh_device_stats_count.restype = size
    lib.voxmesh_mesh_device_stats_count.argtypes = [handle]
    lib.voxmesh_mesh_get_device_stats.restype = status
    lib.voxmesh_mesh_get_device_stats.argtypes = [handle, size, ctypes.POINTER(_DeviceStats)]
    lib.voxmesh_bytes_data.restype = ctypes.c_void_p
    lib.voxmesh_bytes_data.argtypes = [handle]
    lib.voxmesh_bytes_size.restype = size
    lib.voxmesh_bytes_size.argtypes = [handle]
    lib.voxmesh_bytes_free.restype = None
    lib.voxmesh_bytes_free.argtypes = [handle]
    lib.voxmesh_write_mesh_to_memory.restype = status
    lib.voxmesh_write_mesh_to_memory.argtypes = [handle, ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_read_mesh_from_memory.restype = status
    lib.voxmesh_read_mesh_from_memory.argtypes = [ctypes.c_void_p, size, ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_mesh_to_world.restype = status
    lib.voxmesh_mesh_to_world.argtypes = [handle, handle]
    lib.voxmesh_keep_largest_components.restype = status
    lib.voxmesh_keep_largest_components.argtypes = [handle, size, ctypes.POINTER(handle)]
    lib.voxmesh_read_volume_from_memory.restype = status
    lib.voxmesh_read_volume_from_memory.argtypes = [ctypes.c_void_p, size, ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_default_raw_layout.restype = _RawLayout
    lib.voxmesh_default_raw_layout.argtypes = []
    lib.voxmesh_read_raw.restype = status
    lib.voxmesh_read_raw.argtypes = [ctypes.c_char_p, ctypes.POINTER(_RawLayout), ctypes.POINTER(handle)]
    lib.voxmesh_volume_get_info.restype = _VolumeInfo
    lib.voxmesh_volume_get_info.argtypes = [handle]
    lib.voxmesh_write_nrrd.restype = status
    lib.voxmesh_write_nrrd.argtypes = [ctypes.c_char_p, ctypes.POINTER(_VolumeView)]
    lib.voxmesh_write_nrrd_to_memory.restype = status
    lib.voxmesh_write_nrrd_to_memory.argtypes = [ctypes.POINTER(_VolumeView), ctypes.c_char_p, ctypes.POINTER(handle)]
    lib.voxmesh_compute_value_range.restype = status
    lib.voxmesh_compute_value_range.argtypes = [ctypes.POINTER(_VolumeView), ctypes.POINTER(ctypes.c_double),
                                                ctypes.c_uint, ctypes.POINTER(_ValueRange)]
    lib.voxmesh_vertex_edges.restype = status
    lib.voxmesh_vertex_edges.argtypes = [ctypes.POINTER(_VolumeView), ctypes.c_double, ctypes.c_uint, ctypes.c_void_p,
                                         size, ctypes.POINTER(size)]
    lib.voxmesh_triangle_cells.restype = status
    lib.voxmesh_triangle_cells.argtypes = lib.voxmesh_vertex_edges.argtypes
    lib.voxmesh_edge_cell_ranges.restype = status
    lib.voxmesh_edge_cell_ranges.argtypes = [ctypes.POINTER(_VolumeView), ctypes.c_void_p, size, ctypes.c_double,
                                             ctypes.c_void_p, ctypes.c_uint, ctypes.c_void_p]


def _declare_sculpt(lib, handle):
    triple = ctypes.POINTER(ctypes.c_double)
    lib.voxmesh_default_sculpt_options.restype = _SculptOptions
    lib.voxmesh_default_sculpt_options.argtypes = []
    lib.voxmesh_sculpt_new.restype = ctypes.c_int
    lib.voxmesh_sculpt_new.argtypes = [ctypes.POINTER(_VolumeView), ctypes.POINTER(_SculptOptions),
                                       ctypes.POINTER(handle)]
    lib.voxmesh_sculpt_from_mesh.restype = ctypes.c_int
    lib.voxmesh_sculpt_from_mesh.argtypes = [handle, ctypes.POINTER(_VoxelizeOptions), ctypes.POINTER(_SculptOptions),
                                             ctypes.POINTER(handle)]
    lib.voxmesh_sculpt_free.restype = None
    lib.voxmesh_sculpt_free.argtypes = [handle]
    lib.voxmesh_sculpt_apply.restype = ctypes.c_int
    lib.voxmesh_sculpt_apply.argtypes = [handle, ctypes.c_int, triple, ctypes.c_double, ctypes.c_double, ctypes.c_int]
    lib.voxmesh_sculpt_set_region.restype = ctypes.c_int
    lib.voxmesh_sculpt_set_region.argtypes = [handle, triple, triple, ctypes.c_double, ctypes.c_int]
    lib.voxmesh_sculpt_get_view.restype = _VolumeView
    lib.voxmesh_sculpt_get_view.argtypes = [handle]
    lib.voxmesh_sculpt_invalidate_all.restype = ctypes.c_int
    lib.voxmesh_sculpt_invalidate_all.argtypes = [handle]
    lib.voxmesh_sculpt_update.restype = ctypes.c_int
    lib.voxmesh_sculpt_update.argtypes = [handle, ctypes.POINTER(_UpdateResult)]
    lib.voxmesh_sculpt_dirty.restype = ctypes.c_int
    lib.voxmesh_sculpt_dirty.argtypes = [handle]
    lib.voxmesh_sculpt_block_count.restype = ctypes.c_size_t
    lib.voxmesh_sculpt_block_count.argtypes = [handle]
    lib.voxmesh_sculpt_block_grid.restype = None
    lib.voxmesh_sculpt_block_grid.argtypes = [handle, ctypes.POINTER(ctypes.c_size_t)]
    lib.voxmesh_sculpt_get_block.restype = ctypes.c_int
    lib.voxmesh_sculpt_get_block.argtypes = [handle, ctypes.c_size_t, ctypes.POINTER(_Block)]
    lib.voxmesh_sculpt_mesh.restype = ctypes.c_int
    lib.voxmesh_sculpt_mesh.argtypes = [handle, ctypes.POINTER(handle)]
    lib.voxmesh_sculpt_backend.restype = ctypes.c_int
    lib.voxmesh_sculpt_backend.argtypes = [handle]
    lib.voxmesh_sculpt_run_stroke_script.restype = ctypes.c_int
    lib.voxmesh_sculpt_run_stroke_script.argtypes = [handle, ctypes.c_char_p, _STROKE_CALLBACK, ctypes.c_void_p]
    lib.voxmesh_sculpt_run_strokes.restype = ctypes.c_int
    lib.voxmesh_sculpt_run_strokes.argtypes = [handle, ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p,
                                               _STROKE_CALLBACK, ctypes.c_void_p]
    for name in ("voxmesh_sculpt_device_name", "voxmesh_sculpt_warnings"):
        getattr(lib, name).restype = ctypes.c_char_p
        getattr(lib, name).argtypes = [handle]


_lib = _load()


def release_scratch_memory():
    """Frees the scratch memory the CPU engine and the OpenCL devices keep from one extract
    to the next, for a program done meshing large volumes; the next extract allocates anew."""
    _lib.voxmesh_release_scratch_memory()


def devices():
    """The OpenCL devices as dicts (index, type, name, platform, version, compute_units,
    global_memory, max_allocation, fp64, host_memory); [] without OpenCL or a platform. An
    index is what extract(devices=[...]) takes."""
    found = []
    for i in range(_lib.voxmesh_device_count()):
        d = _Device()
        _check(_lib.voxmesh_get_device(i, ctypes.byref(d)))
        found.append({"index": d.index, "type": _DEVICE_TYPE_NAMES.get(d.type, "any"),
                      "name": d.name.decode(errors="replace"), "platform": d.platform.decode(errors="replace"),
                      "version": d.version.decode(errors="replace"), "compute_units": d.compute_units,
                      "global_memory": d.global_memory, "max_allocation": d.max_allocation, "fp64": bool(d.fp64),
                      "host_memory": bool(d.host_memory)})
    return found


def version():
    """The version of the library loaded, e.g. "0.1.0"."""
    return _lib.voxmesh_version().decode()


# The version of the library loaded, which _load checked is the one this package was built for.
__version__ = version()


def _check(status):
    if status == 0:
        return
    message = _lib.voxmesh_last_error().decode(errors="replace")
    raise (VoxmeshMemoryError if status == 2 else VoxmeshError)(message)


class _Handle:
    """Owns one C object; frees it when the last array or wrapper using it is gone."""

    pointer = None  # for an instance __init__ never ran on (copy.deepcopy makes those)

    def __init__(self, pointer, free):
        self.pointer, self._free = pointer, free

    def __del__(self):
        if self.pointer:
            self._free(self.pointer)
            self.pointer = None


class _Memory:
    """Lends `count` elements of library memory to numpy, keeping their owner alive."""

    def __init__(self, address, shape, dtype, owner, readonly):
        self.__array_interface__ = {"shape": shape, "typestr": np.dtype(dtype).str, "data": (address, readonly),
                                    "version": 3}
        self._owner = owner


def _view(address, shape, dtype, owner, readonly=False):
    if not address:
        return np.zeros(shape, dtype=dtype)
    return np.asarray(_Memory(address, shape, dtype, owner, readonly))


class Topology:
    """boundary_edges, nonmanifold_edges, euler, components; closed: no edge in one triangle
    or in three or more."""

    def __init__(self, found):
        self.boundary_edges = found.boundary_edges
        self.nonmanifold_edges = found.nonmanifold_edges
        self.euler = found.euler
        self.components = found.components
        self.closed = self.boundary_edges == 0 and self.nonmanifold_edges == 0

    def __repr__(self):
        return (f"Topology(closed={self.closed}, euler={self.euler}, components={self.components}, "
                f"boundary_edges={self.boundary_edges}, nonmanifold_edges={self.nonmanifold_edges})")


class Mesh:
    """positions (V, 3) float32, normals (V, 3) float32 or None, indices (T, 3) uint32.
    Mesh.from_arrays(positions, indices) makes one from your own arrays (copied)."""

    @classmethod
    def from_arrays(cls, positions, indices):
        positions = np.ascontiguousarray(positions, dtype=np.float32)
        indices = np.asarray(indices)
        if indices.size and indices.dtype.kind not in "iu":
            raise VoxmeshError(f"indices must be integers; got {indices.dtype}")
        if positions.ndim != 2 or positions.shape[1] != 3:
            raise VoxmeshError(f"positions must be shaped (V, 3); got {positions.shape}")
        if indices.ndim != 2 or indices.shape[1] != 3:
            raise VoxmeshError(f"indices must be shaped (T, 3); got {indices.shape}")
        if indices.size and (indices.min() < 0 or indices.max() > np.iinfo(np.uint32).max):
            raise VoxmeshError("indices must be vertex numbers from 0 to 2^32-1")
        indices = np.ascontiguousarray(indices, dtype=np.uint32)
        pointer = ctypes.c_void_p()
        _check(_lib.voxmesh_mesh_from_arrays(positions.ctypes.data, positions.shape[0], indices.ctypes.data,
                                             indices.shape[0], ctypes.byref(pointer)))
        return cls(pointer.value)

    def __init__(self, pointer):
        handle = _Handle(pointer, _lib.voxmesh_mesh_free)
        self._handle = handle
        vertices = _lib.voxmesh_mesh_vertex_count(pointer)
        triangles = _lib.voxmesh_mesh_triangle_count(pointer)
        self.positions = _view(_lib.voxmesh_mesh_positions(pointer), (vertices, 3), np.float32, handle)
        normals = _lib.voxmesh_mesh_normals(pointer)
        self.normals = _view(normals, (vertices, 3), np.float32, handle) if normals else None
        self.indices = _view(_lib.voxmesh_mesh_indices(pointer), (triangles, 3), np.uint32, handle)
        stats = _lib.voxmesh_mesh_stats(pointer)
        # What extract did (None for a mesh it did not make): the backend that ran, the CPU
        # slabs and the threads that ran them, seconds per pass.
        self.stats = None if stats.backend == 0 else {
            "backend": _BACKEND_NAMES[stats.backend], "threads": stats.threads, "workers": stats.workers,
            "classify_s": stats.classify_s, "scan_s": stats.scan_s, "generate_s": stats.generate_s,
            "total_s": stats.total_s, "devices": _device_stats(pointer)}
        # Its warnings (also issued as RuntimeWarning by extract).
        self.warnings = _lib.voxmesh_mesh_warnings(pointer).decode(errors="replace").splitlines()

    def to_bytes(self, format="stl"):
        """The bytes write() would write for a file of that format ("stl", "ply", "obj" or "glb")."""
        if not isinstance(format, str):
            raise VoxmeshError(f"format must be a str (\"stl\", \"ply\", \"obj\" or \"glb\"); got {format!r}")
        return _take_bytes(lambda out: _lib.voxmesh_write_mesh_to_memory(self._handle.pointer,
                                                                          f"mesh.{format}".encode(), out))

    def to_world(self, volume):
        """Moves this mesh, extracted from `volume` (a Volume read from a file), into the file's
        world frame, in place (voxmesh::to_world): positions by volume.info's affine, normals by
        its inverse-transpose, the winding reversed where it mirrors. Nothing changes for a
        volume without a rotation (info["rotation_dropped"] false) or one not read from a file.
        Raises VoxmeshError, leaving the mesh as it was, where a position is not finite or the
        transform would move one beyond the float range."""
        if not isinstance(volume, Volume):
            raise VoxmeshError(f"volume must be a voxmesh.Volume (read_volume's); got {type(volume).__name__}")
        _check(_lib.voxmesh_mesh_to_world(self._handle.pointer, volume._handle.pointer))

    def largest_components(self, count=1):
        """The `count` connected pieces with the most triangles, in their order (a CT's surface
        without the specks of noise around it); normals kept."""
        count = _whole_number("count", count, f"count must be at least 1; got {count}")
        pointer = ctypes.c_void_p()
        _check(_lib.voxmesh_keep_largest_components(self._handle.pointer, count, ctypes.byref(pointer)))
        return Mesh(pointer.value)

    @property
    def vertex_count(self):
        return self.positions.shape[0]

    @property
    def triangle_count(self):
        return self.indices.shape[0]

    def write(self, path):
        """.stl, .ply, .obj or .glb (binary glTF 2.0) by extension, through a temporary file renamed into place."""
        _check(_lib.voxmesh_write_mesh(_path(path), self._handle.pointer))

    def topology(self):
        """voxmesh::analyze_topology: closed or not, Euler characteristic, connected pieces."""
        found = _Topology()
        _check(_lib.voxmesh_analyze_topology(self._handle.pointer, ctypes.byref(found)))
        return Topology(found)


def _device_stats(pointer):
    """Per device of an extract: "cpu" or an OpenCL device, with its chunks and seconds."""
    found = []
    for i in range(_lib.voxmesh_mesh_device_stats_count(pointer)):
        d = _DeviceStats()
        _check(_lib.voxmesh_mesh_get_device_stats(pointer, i, ctypes.byref(d)))
        found.append({"name": d.name.decode(errors="replace"), "chunks": d.chunks, "voxels": d.voxels,
                      "kernel_s": d.kernel_s, "transfer_s": d.transfer_s, "wall_s": d.wall_s, "setup_s": d.setup_s,
                      "programs_built": d.programs_built, "chunks_handed_over": d.chunks_handed_over})
    return found


def _take_bytes(write):
    """Runs write(&bytes) and returns the library's bytes as a Python bytes object."""
    pointer = ctypes.c_void_p()
    _check(write(ctypes.byref(pointer)))
    try:
        size = _lib.voxmesh_bytes_size(pointer)
        return ctypes.string_at(_lib.voxmesh_bytes_data(pointer), size) if size else b""
    finally:
        _lib.voxmesh_bytes_free(pointer)


class Volume:
    """A volume read from a file or voxelized: `array` [z, y, x], `spacing` and `origin` as
    (x, y, z). A file's samples are read-only (they may be the file itself, mapped). `info`
    is what the file said beyond the samples (None for a voxelized volume): format, encoding,
    big_endian, flipped (axes stored reversed, turned on load), rotation_dropped, NIfTI's
    value_scale and value_offset (not applied: a physical iso p is (p - offset) / scale), and
    the file's world transform: sample (i, j, k) lies at world_origin + directions @ ((i, j, k) *
    spacing), directions 3 rows of 3 (a tuple) whose column a is axis a's unit direction (the identity,
    and world_origin the origin, unless rotation_dropped; Mesh.to_world applies it)."""

    def __init__(self, pointer, readonly=True):
        handle = _Handle(pointer, _lib.voxmesh_volume_free)
        self._handle = handle
        view = _lib.voxmesh_volume_get_view(pointer)
        nx, ny, nz = view.dims
        self.array = _view(view.data, (nz, ny, nx), _DTYPES[view.type], handle, readonly=readonly)
        self.spacing = tuple(view.spacing)
        self.origin = tuple(view.origin)
        info = _lib.voxmesh_volume_get_info(pointer)
        self.info = None if not info.format else {
            "format": info.format.decode(), "encoding": info.encoding.decode(), "big_endian": bool(info.big_endian),
            "flipped": tuple(bool(f) for f in info.flipped), "rotation_dropped": bool(info.rotation_dropped),
            "value_scale": info.value_scale, "value_offset": info.value_offset,
            "directions": tuple(tuple(info.directions[3 * c:3 * c + 3]) for c in range(3)),
            "world_origin": tuple(info.world_origin)}


def _is_bytes(source):
    return isinstance(source, (bytes, bytearray, memoryview))


def _path(path):
    """A path (str, bytes or os.PathLike) as the C API takes it. A NUL would end it early
    there, naming another file: refused, as open() refuses it."""
    encoded = os.fsencode(path)
    if b"\0" in encoded:
        raise ValueError(f"embedded null byte in the path {path!r}")
    return encoded


def _bytes_call(source, name, call):
    """call(address, size, name, &object) over the bytes of `source`; `name` says the format."""
    if not name:
        raise VoxmeshError("reading bytes needs name=, whose extension says the format (e.g. 'scan.nrrd')")
    if isinstance(source, memoryview) and not source.c_contiguous:
        raise VoxmeshError("the bytes must be contiguous; got a non-contiguous memoryview (pass bytes(view))")
    data = np.frombuffer(source, dtype=np.uint8)  # no copy; the library copies what it keeps
    pointer = ctypes.c_void_p()
    _check(call(data.ctypes.data if data.size else None, data.size, _path(name), ctypes.byref(pointer)))
    return pointer.value


def read_mesh(source, name=None):
    """STL (binary or ASCII), PLY or OBJ, chosen by extension, as voxmesh::read_mesh. `source`
    is a path, or the file's bytes with `name` ("part.stl") standing for its path."""
    if _is_bytes(source):
        return Mesh(_bytes_call(source, name, _lib.voxmesh_read_mesh_from_memory))
    pointer = ctypes.c_void_p()
    _check(_lib.voxmesh_read_mesh(_path(source), ctypes.byref(pointer)))
    return Mesh(pointer.value)


_UINT_MAX = 2 ** (8 * ctypes.sizeof(ctypes.c_uint)) - 1
_SIZE_MAX = 2 ** (8 * ctypes.sizeof(ctypes.c_size_t)) - 1
# The C fields' widths: ctypes would keep a larger number's low bits without a word
# (threads=2**32 became 0, every CPU; 2**32 + 1 one thread).
_LIMITS = {"threads": _UINT_MAX}


def _integer(name, value):
    """value as an int (a Python or numpy integer); anything else, a float or a bool included, is
    a VoxmeshError rather than a number cut to its whole part."""
    if isinstance(value, (bool, np.bool_)):
        raise VoxmeshError(f"{name} must be a whole number; got {value!r}")
    try:
        return operator.index(value)
    except TypeError:
        raise VoxmeshError(f"{name} must be a whole number; got {value!r}") from None


def _whole_number(name, value, negative_message):
    """value as an int that fits its C field (threads: unsigned int, sizes: size_t); a float,
    a negative number or one too large is a VoxmeshError."""
    number = _integer(name, value)
    if number < 0:
        raise VoxmeshError(negative_message)
    limit = _LIMITS.get(name, _SIZE_MAX)
    if number > limit:
        raise VoxmeshError(f"{name} must be at most {limit}; got {value}")
    return number


_INT_MAX = 2 ** (8 * ctypes.sizeof(ctypes.c_int) - 1) - 1


def _real(name, value):
    """value as a float: a Python or numpy real number, not a string, a bool or a complex (float()
    parsed '0.5'); one beyond a double's range is a VoxmeshError, not an OverflowError."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value.item()  # a 0-d array, as some numpy reductions give
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise VoxmeshError(f"{name} must be a real number; got {value!r}")
    try:
        return float(value)
    except OverflowError:
        raise VoxmeshError(f"{name} {value} is beyond the range of a double") from None


def _device_list(devices):
    """extract's devices: None (every device of device_type), one index, or a sequence of them."""
    if devices is None:
        return []
    if isinstance(devices, (numbers.Integral, np.integer)) and not isinstance(devices, (bool, np.bool_)):
        return [_device_index("devices", devices)]
    if isinstance(devices, (str, bytes)):
        raise VoxmeshError(f"devices must be device indices (voxmesh.devices()); got {devices!r}")
    try:
        items = list(devices)
    except TypeError:
        raise VoxmeshError(f"devices must be device indices (voxmesh.devices()); got {devices!r}") from None
    return [_device_index("devices[]", d) for d in items]


def _device_index(name, value, allow_every=False):
    """An OpenCL device index as the C int it is passed as (-1: every device, where allowed);
    ctypes would keep a larger number's low bits and run on another device."""
    number = _integer(name, value)
    low = -1 if allow_every else 0
    if not low <= number <= _INT_MAX:
        raise VoxmeshError(f"{name} must be a device index from {low} to {_INT_MAX}; got {value}")
    return number


def _check_automatic(**values):
    """Numbers where 0 means automatic (threads, chunk sizes): refused when negative, not whole
    or beyond their C field."""
    for name, value in values.items():
        _whole_number(name, value, f"{name} must be 0 (automatic) or more; got {value}")


_FIELDS = {"occupancy": 0, "distance": 1}
_FILLS = {"evenodd": 0, "nonzero": 1}


def _voxelize_options(resolution, padding, field, band, threads, fill="evenodd"):
    if field not in _FIELDS:
        raise VoxmeshError(f"unknown field '{field}' (distance, occupancy)")
    if fill not in _FILLS:
        raise VoxmeshError(f"unknown fill rule '{fill}' (evenodd, nonzero)")
    for name, value in (("resolution", resolution), ("padding", padding), ("threads", threads)):
        _whole_number(name, value, f"{name} must not be negative; got {value}")
    options = _lib.voxmesh_default_voxelize_options()
    options.resolution = int(resolution)
    options.padding = int(padding)
    options.field = _FIELDS[field]
    options.band = _real("band", band)
    options.threads = int(threads)
    options.fill = _FILLS[fill]
    return options


def voxelize(mesh, resolution=128, padding=2, field="distance", band=3.0, threads=0, fill="evenodd"):
    """A closed mesh (a Mesh, or a (positions, indices) pair) as a Volume, as voxmesh::voxelize:
    field "distance" (float32, positive inside: extract it at iso 0) or "occupancy" (uint8, 255
    inside: extract it at iso 127.5); spacing and origin put its mesh back in the model's units.
    fill "evenodd" (inside after an odd number of crossings, any winding) or "nonzero" (the union
    of overlapping or nested closed shells; needs consistent winding)."""
    if not isinstance(mesh, Mesh):
        mesh = Mesh.from_arrays(*mesh)
    options = _voxelize_options(resolution, padding, field, band, threads, fill)
    pointer = ctypes.c_void_p()
    _check(_lib.voxmesh_voxelize(mesh._handle.pointer, ctypes.byref(options), ctypes.byref(pointer)))
    return Volume(pointer.value, readonly=False)


def _three(value, what):
    """`value`'s three items as a list; else VoxmeshError("{what}; got ...")."""
    try:
        items = list(value)
    except TypeError:
        raise VoxmeshError(f"{what}; got {value!r}") from None
    if len(items) != 3:
        raise VoxmeshError(f"{what}; got {len(items)} values")
    return items


def _triple(name, value, default):
    if value is None:
        return [default] * 3
    return [_real(name, v) for v in _three(value, f"{name} must be three numbers (x, y, z)")]


def _unwrap(volume, spacing, origin):
    """The samples of an array or a Volume, with a Volume's spacing and origin where none are given."""
    if isinstance(volume, Volume):
        spacing = volume.spacing if spacing is None else spacing
        origin = volume.origin if origin is None else origin
        volume = volume.array
    return np.asarray(volume), spacing, origin


def _as_view(volume, spacing, origin):
    """A C view of a 3-D array [z, y, x] or a Volume, and the array it points into (keep it
    alive while the view is used)."""
    array, spacing, origin = _unwrap(volume, spacing, origin)
    if array.ndim != 3:
        raise VoxmeshError(f"volume must be 3-D, indexed [z, y, x]; got {array.ndim} dimension(s)")
    if array.dtype == np.bool_:
        array = array.view(np.uint8)
    native = array.dtype.newbyteorder("=")
    if native.type not in _DTYPES:
        raise VoxmeshError(f"unsupported sample type {array.dtype} (uint8, int8, uint16, int16, uint32, "
                           "int32, float32, float64: convert first, e.g. volume.astype(np.float32))")
    array = np.require(array, native, ["C", "A"])  # a copy only where layout or alignment needs one
    view = _VolumeView()
    view.data = array.ctypes.data
    view.type = _DTYPES.index(native.type)
    view.dims[:] = [array.shape[2], array.shape[1], array.shape[0]]
    view.spacing[:] = _triple("spacing", spacing, 1.0)
    view.origin[:] = _triple("origin", origin, 0.0)
    return view, array


def read_volume(source, name=None):
    """NRRD, MetaImage, NIfTI-1, legacy VTK or NumPy .npy, chosen by extension, as voxmesh::read_volume.
    `source` is a path, or the file's bytes with `name` ("scan.nii.gz") standing for its path."""
    if _is_bytes(source):
        return Volume(_bytes_call(source, name, _lib.voxmesh_read_volume_from_memory), readonly=False)
    pointer = ctypes.c_void_p()
    _check(_lib.voxmesh_read_volume(_path(source), ctypes.byref(pointer)))
    return Volume(pointer.value)


def read_raw(path, shape, dtype, big_endian=None, offset=0, spacing=None, origin=None):
    """Headerless samples: `shape` is the array's (nz, ny, nx), `dtype` one of the eight sample
    types; the file holds exactly offset + nx * ny * nz samples' bytes. The byte order is the
    dtype's where it names one ('>f4', '<i2'), else big_endian's (default little-endian); the
    two disagreeing is an error. spacing and origin are (x, y, z); a negative spacing runs its
    axis the other way (reversed on load)."""
    sizes = _three(shape, "shape must be three sizes (nz, ny, nx)")
    sizes = [_whole_number("shape", n, f"shape must be three sizes (nz, ny, nx); got {sizes}") for n in sizes]
    given = np.dtype(dtype)
    native = given.newbyteorder("=")
    if native.type not in _DTYPES:
        raise VoxmeshError(f"unsupported sample type {given} (uint8, int8, uint16, int16, uint32, "
                           "int32, float32, float64)")
    # numpy writes the machine's own order as '=', so '<f4' is told from 'f4' by the string.
    order = dtype[0] if isinstance(dtype, str) and dtype[:1] in "<>" else given.byteorder
    if order in "<>" and given.itemsize > 1:
        if big_endian is not None and bool(big_endian) != (order == ">"):
            raise VoxmeshError(f"dtype '{given.str}' is {'big' if order == '>' else 'little'}-endian but "
                               f"big_endian={big_endian!r}")
        big_endian = order == ">"
    offset = _whole_number("offset", offset, f"offset must not be negative; got {offset}")
    layout = _lib.voxmesh_default_raw_layout()
    layout.dims[:] = sizes[::-1]
    layout.type = _DTYPES.index(native.type)
    layout.big_endian = 1 if big_endian else 0
    layout.offset = offset
    layout.spacing[:] = _triple("spacing", spacing, 1.0)
    layout.origin[:] = _triple("origin", origin, 0.0)
    pointer = ctypes.c_void_p()
    _check(_lib.voxmesh_read_raw(_path(path), ctypes.byref(layout), ctypes.byref(pointer)))
    return Volume(pointer.value)


def write_nrrd(path, volume, spacing=None, origin=None):
    """A volume (an array [z, y, x] or a Volume) as NRRD, through a temporary file renamed into
    place; path None returns the bytes instead. spacing and origin are (x, y, z)."""
    view, array = _as_view(volume, spacing, origin)  # `array` keeps the samples alive for the call
    if path is None:
        return _take_bytes(lambda out: _lib.voxmesh_write_nrrd_to_memory(ctypes.byref(view), b"volume.nrrd", out))
    _check(_lib.voxmesh_write_nrrd(_path(path), ctypes.byref(view)))
    del array


def extract(volume, iso=0.0, spacing=None, origin=None, backend="auto", threads=0, normals=True,
            inside_below=False, devices=None, device_type="any", chunk_planes=0, memory_budget=0):
    """The iso-surface of `volume` (a 3-D array [z, y, x] or a Volume) at `iso` as a Mesh.

    A sample is inside when value >= iso (value < iso with inside_below, for signed distance
    fields). backend: "auto", "cpu", "opencl" or "hybrid"; threads 0: every CPU this process may
    use. spacing and origin are (x, y, z); a Volume brings its own unless they are given.
    devices: OpenCL device indices (voxmesh.devices()), or one index; device_type: "any", "cpu", "gpu" or
    "accelerator". chunk_planes (z-planes per chunk) and memory_budget (bytes per device for one
    chunk) size the OpenCL chunks; 0: automatic. Every backend, thread count, device and chunk
    size gives the same mesh.
    """
    if backend not in _BACKENDS:
        raise VoxmeshError(f"unknown backend '{backend}' (auto, cpu, opencl, hybrid)")
    if device_type not in _DEVICE_TYPES:
        raise VoxmeshError(f"unknown device type '{device_type}' (any, cpu, gpu, accelerator)")
    chosen = _device_list(devices)
    _check_automatic(threads=threads, chunk_planes=chunk_planes, memory_budget=memory_budget)
    view, array = _as_view(volume, spacing, origin)  # `array` keeps the samples alive for the call
    options = _lib.voxmesh_default_options()
    options.iso = _real("iso", iso)
    options.backend = _BACKENDS[backend]
    options.threads = int(threads)
    options.normals = 1 if normals else 0
    options.inside_below = 1 if inside_below else 0
    device_array = (ctypes.c_int * max(1, len(chosen)))(*chosen)  # alive until the call returns
    options.devices = ctypes.cast(device_array, ctypes.POINTER(ctypes.c_int)) if chosen else None
    options.device_count = len(chosen)
    options.device_type = _DEVICE_TYPES[device_type]
    options.chunk_planes = int(chunk_planes)
    options.memory_budget = int(memory_budget)
    pointer = ctypes.c_void_p()
    _check(_lib.voxmesh_extract(ctypes.byref(view), ctypes.byref(options), ctypes.byref(pointer)))
    mesh = Mesh(pointer.value)
    for message in mesh.warnings:
        warnings.warn(message, RuntimeWarning, stacklevel=2)
    return mesh


# value_range(): the smallest and largest finite sample, the NaN or infinite ones (count, and the
# first's array index (z, y, x), None without one), and the samples equal to equal_to.
ValueRange = collections.namedtuple("ValueRange", "min max nonfinite first_nonfinite equal")


def value_range(volume, equal_to=None, threads=0):
    """A volume's samples summed up in one pass on all cores, as a ValueRange: min and max of the
    finite samples (0.0 when none is), how many are NaN or infinite and where the first is, and
    how many finite samples equal `equal_to` exactly (0 when it is None). Samples exactly at an iso value are
    inside for extract and outside for scikit-image: they are where the two meshes differ."""
    _check_automatic(threads=threads)
    view, array = _as_view(volume, None, None)  # `array` keeps the samples alive for the call
    result = _ValueRange()
    target = None if equal_to is None else ctypes.byref(ctypes.c_double(_real("equal_to", equal_to)))
    _check(_lib.voxmesh_compute_value_range(ctypes.byref(view), target, int(threads), ctypes.byref(result)))
    del array
    first = tuple(result.first_nonfinite)[::-1] if result.nonfinite else None
    return ValueRange(result.min, result.max, result.nonfinite, first, result.equal)


def vertex_edges(volume, iso=0.0, threads=0, count=None):
    """The crossed edge under each vertex of extract(volume, iso), as a uint64 array: vertex i
    lies on edges[i] = 3 * s + axis, s the flat index of its lower end in the [z, y, x] array
    (volume.ravel()'s) and axis 0 for x, 1 for y, 2 for z. For data kept per sample (labels, a
    second field) carried onto the mesh: with `s, axis = np.divmod(edges, 3)`, a vertex's two
    samples are s and s + (1, nx, nx * ny)[axis]. count: the mesh's vertex count when known
    (saves a pass; a wrong one is an error)."""
    return _list_query(_lib.voxmesh_vertex_edges, volume, iso, threads, count, "vertex", "crossed edges")


def triangle_cells(volume, iso=0.0, threads=0, count=None):
    """The cell each triangle of extract(volume, iso) lies in, as a uint64 array: triangle i lies
    in the cell whose lowest corner is sample [z, y, x] with cells[i] = x + (nx-1) * (y + (ny-1)
    * z), the flat index into an array of the cells' shape (nz-1, ny-1, nx-1). For data kept per
    cell (a mask, a material) carried onto the triangles: `mesh.indices[cell_mask.ravel()[cells]]`
    are the triangles of the cells a mask keeps. count: the mesh's triangle count when known
    (saves a pass; a wrong one is an error)."""
    return _list_query(_lib.voxmesh_triangle_cells, volume, iso, threads, count, "triangle", "triangles")


def _list_query(call, volume, iso, threads, count, per, found_what):
    """A uint64 array from one of the C calls that list one entry per vertex or triangle
    (voxmesh_vertex_edges, voxmesh_triangle_cells): asked for the count first unless given."""
    _check_automatic(threads=threads)
    if count is not None:
        count = _whole_number("count", count, f"count must be the mesh's {per} count, not negative; got {count}")
    view, array = _as_view(volume, None, None)  # `array` keeps the samples alive for the call
    found = ctypes.c_size_t()
    if count is None:
        _check(call(ctypes.byref(view), _real("iso", iso), int(threads), None, 0, ctypes.byref(found)))
        count = found.value
    try:
        out = np.empty(count, dtype=np.uint64)
    except (ValueError, MemoryError):
        raise VoxmeshError(f"count {count}: no room for that many {found_what}") from None
    _check(call(ctypes.byref(view), _real("iso", iso), int(threads), out.ctypes.data, len(out), ctypes.byref(found)))
    if found.value != len(out):
        raise VoxmeshError(f"count {len(out)} given, but the volume has {found.value} {found_what}")
    del array
    return out


def edge_cell_ranges(volume, edges, offset=0.0, cell_mask=None, threads=0):
    """For each edge (vertex_edges' numbering), the largest range, maximum minus minimum sample,
    over the cells around it (up to four) that the volume holds and `cell_mask` marks True, as
    float32; 0 where none counts. cell_mask: None or an array of the cells' shape (nz-1, ny-1,
    nx-1), a cell by its lowest corner. Each range is (max - offset) - (min - offset) in double:
    with offset = the level, scikit-image's `values` from marching_cubes. Samples must be finite
    (vertex_edges refuses others); ranges over NaN are unspecified."""
    _check_automatic(threads=threads)
    view, array = _as_view(volume, None, None)
    edges = np.asarray(edges)
    if edges.ndim != 1:
        raise VoxmeshError(f"edges must be a 1-D array; got {edges.ndim} dimension(s)")
    if len(edges) and edges.dtype.kind not in "iu":
        raise VoxmeshError(f"edges must be integers (vertex_edges' numbering); got {edges.dtype}")
    if len(edges) and edges.dtype.kind == "i" and edges.min() < 0:
        raise VoxmeshError(f"edges must not be negative; got {edges.min()}")
    edges = np.ascontiguousarray(edges, dtype=np.uint64)
    mask = None
    # A volume under 2 samples on an axis has no cells: the library names that, not the mask.
    if cell_mask is not None and min(array.shape) >= 2:
        cells = tuple(n - 1 for n in array.shape)
        mask = np.ascontiguousarray(cell_mask, dtype=bool)
        if mask.shape != cells:
            raise VoxmeshError(f"cell_mask must have the cells' shape {cells}; got {mask.shape}")
    ranges = np.empty(len(edges), dtype=np.float32)
    _check(_lib.voxmesh_edge_cell_ranges(ctypes.byref(view), edges.ctypes.data, len(edges), _real("offset", offset),
                                         None if mask is None else mask.ctypes.data, int(threads), ranges.ctypes.data))
    del array, mask
    return ranges


_BRUSHES = {"add": 0, "subtract": 1, "smooth": 2, "set": 3}
_UNITS = {"samples": 0, "world": 1}
_BRUSH_NAMES = {code: name for name, code in _BRUSHES.items()}
_UNIT_NAMES = {code: name for name, code in _UNITS.items()}

# update(): the blocks re-meshed that are or were non-empty (ascending), how many dirty blocks
# were re-meshed (empty ones included), and the seconds it took.
UpdateResult = collections.namedtuple("UpdateResult", "changed remeshed seconds")
# One block's own mesh (copied: a block's arrays change at the next update). index is
# bx + nbx * (by + nby * bz); coord, cell_begin and cell_end are (x, y, z); positions (V, 3)
# float32, normals (V, 3) float32 or None, indices (T, 3) uint32 into this block's vertices.
Block = collections.namedtuple("Block", "index coord cell_begin cell_end positions normals indices")
# One dab of a stroke script, after it was applied and meshed: frame (0-based), line (1-based),
# brush ("add", ...), units ("samples" or "world"), center (x, y, z), radius, strength, the
# seconds of its edit and of its update, and the blocks that update changed and re-meshed.
StrokeFrame = collections.namedtuple("StrokeFrame", "frame line brush units center radius strength edit_seconds "
                                                    "update_seconds blocks_changed blocks_remeshed")


def _run_strokes(call, on_frame):
    """call(callback) with on_frame told each frame as a StrokeFrame; an exception from on_frame
    stops the strokes and is raised here (the C library cannot carry it)."""
    raised = []

    def tell(frame, _user):
        f = frame.contents
        try:
            on_frame(StrokeFrame(f.frame, f.line, _BRUSH_NAMES[f.brush], _UNIT_NAMES[f.units], tuple(f.center),
                                 f.radius, f.strength, f.edit_seconds, f.update_seconds, f.blocks_changed,
                                 f.blocks_remeshed))
        except BaseException as error:  # noqa: B902 - KeyboardInterrupt stops the strokes too
            raised.append(error)
            return 1
        return 0

    callback = _STROKE_CALLBACK(tell) if on_frame is not None else _STROKE_CALLBACK()
    status = call(callback)
    if raised:
        raise raised[0]
    _check(status)


def _sculpt_options(iso, threads, block_size, normals, inside_below, strength_scale, backend, device):
    if backend not in _BACKENDS:
        raise VoxmeshError(f"unknown backend '{backend}' (cpu, opencl, auto)")
    for name, value in (("threads", threads), ("block_size", block_size)):
        _whole_number(name, value, f"{name} must not be negative; got {value}")
    options = _lib.voxmesh_default_sculpt_options()
    options.iso = _real("iso", iso)
    options.threads = int(threads)
    options.block_size = int(block_size)
    options.normals = 1 if normals else 0
    options.inside_below = 1 if inside_below else 0
    options.strength_scale = _real("strength_scale", strength_scale)
    options.backend = _BACKENDS[backend]
    options.device = _device_index("device", device, allow_every=True)
    return options


def _point(name, value):
    return (ctypes.c_double * 3)(*_triple(name, value, None))


class Sculpt:
    """An editable copy of a volume whose surface is kept as a mesh in blocks (voxmesh::Sculpt):
    a brush dab marks the blocks it can change, update() re-meshes only those, and mesh() welds
    them into exactly extract()'s mesh of the edited samples.

        sculpt = voxmesh.Sculpt(volume, iso=0.0, block_size=32)   # an array [z, y, x] or a Volume
        sculpt.add((x, y, z), radius=6, strength=2)               # sample coordinates (units="world" too)
        result = sculpt.update()                                  # result.changed: blocks to redraw
        block = sculpt.block(result.changed[0])                   # that block's own mesh
        mesh = sculpt.mesh()

    The samples are copied: uint8 and uint16 as they are, other types as float32.
    Brushes: add / subtract change the field by strength * strength_scale with a smooth falloff
    inside the radius; smooth moves samples toward their neighbours' mean (strength 0..1); set_region
    sets a box. `array` is the samples themselves, writable: write to it, then invalidate_all().
    backend "opencl" (or "auto": a GPU when there is one) re-meshes on an OpenCL device.
    Calls from several threads take turns (a lock; on_frame may call back into the sculpt);
    writes to `array` are not covered by it.
    """

    def __init__(self, volume, iso=0.0, spacing=None, origin=None, threads=0, block_size=32, normals=True,
                 inside_below=False, strength_scale=0.0, backend="cpu", device=-1):
        options = _sculpt_options(iso, threads, block_size, normals, inside_below, strength_scale, backend, device)
        volume, spacing, origin = _unwrap(volume, spacing, origin)
        if volume.dtype.type not in (np.uint8, np.uint16, np.float32, np.bool_):
            # The sculpt keeps u8, u16 or f32 samples in a copy of its own: make that copy float32.
            volume = volume.astype(np.float32)
        view, _samples = _as_view(volume, spacing, origin)  # alive for the call; the library copies them
        pointer = ctypes.c_void_p()
        _check(_lib.voxmesh_sculpt_new(ctypes.byref(view), ctypes.byref(options), ctypes.byref(pointer)))
        self._adopt(pointer.value, normals)

    def _adopt(self, pointer, normals):
        self._handle = _Handle(pointer, _lib.voxmesh_sculpt_free)
        # Every C call releases the GIL and the C++ Sculpt is not thread-safe: one call at a
        # time. Re-entrant, since run_strokes' on_frame runs inside a call on the same thread.
        self._lock = threading.RLock()
        self._normals = bool(normals)  # an empty block's normals are then an empty array, not None
        view = _lib.voxmesh_sculpt_get_view(pointer)
        nx, ny, nz = view.dims
        # The samples [z, y, x], writable; call invalidate_all() after writing to them.
        self.array = _view(view.data, (nz, ny, nx), _DTYPES[view.type], self._handle)
        self.spacing = tuple(view.spacing)
        self.origin = tuple(view.origin)
        for message in self.warnings:
            warnings.warn(message, RuntimeWarning, stacklevel=3)

    @classmethod
    def from_mesh(cls, model, resolution=128, padding=2, band=4.0, threads=0, block_size=32, normals=True,
                  strength_scale=0.0, backend="cpu", device=-1, fill="evenodd"):
        """A closed model (a Mesh, or a (positions, indices) pair) voxelized to a signed distance
        field with `resolution` voxels along its longest side and `padding` samples around it:
        float32, positive inside, iso 0, in the model's units; brush strengths are in voxels of
        surface displacement. A surface built up past the padding is cut open at the border.
        fill: as voxelize's ("nonzero" for overlapping bodies)."""
        if not isinstance(model, Mesh):
            model = Mesh.from_arrays(*model)
        grid = _voxelize_options(resolution, padding, "distance", band, threads, fill)
        options = _sculpt_options(0.0, threads, block_size, normals, False, strength_scale, backend, device)
        pointer = ctypes.c_void_p()
        _check(_lib.voxmesh_sculpt_from_mesh(model._handle.pointer, ctypes.byref(grid), ctypes.byref(options),
                                             ctypes.byref(pointer)))
        sculpt = cls.__new__(cls)
        sculpt._adopt(pointer.value, normals)
        return sculpt

    def apply(self, brush, center, radius, strength=1.0, units="samples"):
        """One dab: brush "add", "subtract", "smooth" or "set" (the box center +- radius :=
        strength) at center (x, y, z), in "samples" (index) or "world" units."""
        if brush not in _BRUSHES:
            raise VoxmeshError(f"unknown brush '{brush}' (add, subtract, smooth, set)")
        if units not in _UNITS:
            raise VoxmeshError(f"unknown units '{units}' (samples, world)")
        center, radius, strength = _point("center", center), _real("radius", radius), _real("strength", strength)
        with self._lock:
            _check(_lib.voxmesh_sculpt_apply(self._handle.pointer, _BRUSHES[brush], center, radius, strength,
                                             _UNITS[units]))

    def add(self, center, radius, strength=1.0, units="samples"):
        self.apply("add", center, radius, strength, units)

    def subtract(self, center, radius, strength=1.0, units="samples"):
        self.apply("subtract", center, radius, strength, units)

    def smooth(self, center, radius, strength=0.5, units="samples"):
        self.apply("smooth", center, radius, strength, units)

    def set_region(self, lo, hi, value, units="samples"):
        """Every sample with lo <= coordinate <= hi on each axis := value (clamped to the type)."""
        if units not in _UNITS:
            raise VoxmeshError(f"unknown units '{units}' (samples, world)")
        lo, hi, value = _point("lo", lo), _point("hi", hi), _real("value", value)
        with self._lock:
            _check(_lib.voxmesh_sculpt_set_region(self._handle.pointer, lo, hi, value, _UNITS[units]))

    def run_strokes(self, script, name="strokes", on_frame=None):
        """A stroke script's text (str or bytes): one dab a line, "op x y z radius strength" with
        op add | subtract | smooth | set, '#' comments, and "units world" / "units samples" lines.
        The whole script is read first: a malformed line raises VoxmeshError "NAME:LINE: problem"
        with nothing applied. Then each dab is applied and meshed, and on_frame(StrokeFrame)
        called; an exception from on_frame stops the strokes there and is raised."""
        text = script.encode() if isinstance(script, str) else bytes(script)
        name = _path(str(name))
        with self._lock:
            _run_strokes(lambda callback: _lib.voxmesh_sculpt_run_strokes(self._handle.pointer, text, len(text),
                                                                          name, callback, None), on_frame)

    def run_stroke_script(self, path, on_frame=None):
        """run_strokes with the script read from the file at `path` (errors name the file)."""
        path = _path(path)
        with self._lock:
            _run_strokes(lambda callback: _lib.voxmesh_sculpt_run_stroke_script(self._handle.pointer, path,
                                                                                callback, None), on_frame)

    def invalidate_all(self):
        """Marks every block dirty after writes to `array`; refuses NaN or infinite samples."""
        with self._lock:
            _check(_lib.voxmesh_sculpt_invalidate_all(self._handle.pointer))

    def update(self):
        """Re-meshes the dirty blocks; an UpdateResult."""
        result = _UpdateResult()
        with self._lock:  # result.changed lives until the next update
            _check(_lib.voxmesh_sculpt_update(self._handle.pointer, ctypes.byref(result)))
            changed = [result.changed[i] for i in range(result.changed_count)]
        return UpdateResult(changed, result.remeshed, result.seconds)

    @property
    def dirty(self):
        """Edits not yet meshed."""
        with self._lock:
            return bool(_lib.voxmesh_sculpt_dirty(self._handle.pointer))

    @property
    def block_count(self):
        with self._lock:
            return _lib.voxmesh_sculpt_block_count(self._handle.pointer)

    @property
    def block_grid(self):
        """Blocks per axis (x, y, z)."""
        grid = (ctypes.c_size_t * 3)()
        with self._lock:
            _lib.voxmesh_sculpt_block_grid(self._handle.pointer, grid)
        return tuple(grid)

    def block(self, index):
        """Block `index`'s mesh as of the last update (a Block of copies)."""
        index = _integer("index", index)
        with self._lock:  # the block's arrays change at the next update: copied under the lock
            if not 0 <= index < self.block_count:
                raise VoxmeshError(f"block {index} does not exist ({self.block_count} blocks)")
            found = _Block()
            _check(_lib.voxmesh_sculpt_get_block(self._handle.pointer, index, ctypes.byref(found)))
            v, t = found.vertex_count, found.triangle_count
            positions = _view(found.positions, (v, 3), np.float32, None).copy()
            # The C API gives no array (NULL) for an empty one: None only where normals are off.
            normals = _view(found.normals, (v, 3), np.float32, None).copy() if found.normals else None
            indices = _view(found.indices, (t, 3), np.uint32, None).copy()
        if normals is None and self._normals:
            normals = np.empty((0, 3), np.float32)
        return Block(found.index, tuple(found.coord), tuple(found.cell_begin), tuple(found.cell_end), positions,
                     normals, indices)

    def mesh(self):
        """The whole welded mesh, exactly extract()'s of the samples (updates first)."""
        pointer = ctypes.c_void_p()
        with self._lock:
            _check(_lib.voxmesh_sculpt_mesh(self._handle.pointer, ctypes.byref(pointer)))
        return Mesh(pointer.value)

    @property
    def backend(self):
        """Where update() re-meshes: "cpu" or "opencl"."""
        with self._lock:
            return _BACKEND_NAMES[_lib.voxmesh_sculpt_backend(self._handle.pointer)]

    @property
    def device_name(self):
        """"cpu" or the OpenCL device's name."""
        with self._lock:  # the text lives in the sculpt until the next call
            return _lib.voxmesh_sculpt_device_name(self._handle.pointer).decode(errors="replace")

    @property
    def warnings(self):
        """The library's warnings so far (a fallback to the CPU), also issued as RuntimeWarning."""
        with self._lock:
            return _lib.voxmesh_sculpt_warnings(self._handle.pointer).decode(errors="replace").splitlines()


from ._skimage import marching_cubes  # noqa: E402  (uses extract, defined above)
