"""voxmesh.marching_cubes: a drop-in for skimage.measure.marching_cubes (scikit-image 0.19),
meshed by voxmesh.extract. Kept apart from __init__.py because it is only a translation of
arguments and results; the meshing is extract's."""

import numpy as np

from . import VoxmeshError, extract, vertex_edges, triangle_cells, edge_cell_ranges, value_range, _BACKENDS

_METHODS = ("lewiner", "lorensen")
_NO_SURFACE = "No surface found at the given iso value."  # skimage's RuntimeError, word for word
# Types whose every value float32 holds: skimage converts to float32 first, and meshing these
# as they are gives the same crossings and the same t without the copy.
_EXACT_IN_FLOAT32 = (np.uint8, np.int8, np.uint16, np.int16, np.float32)


def marching_cubes(volume, level=None, *, spacing=(1.0, 1.0, 1.0), gradient_direction="descent", step_size=1,
                   allow_degenerate=True, method="lewiner", mask=None, threads=0, backend="auto"):
    """The iso-surface of `volume` at `level` as skimage.measure.marching_cubes gives it:
    (verts, faces, normals, values).

    Arguments and results mean what they mean in scikit-image 0.19; threads and backend are
    extract's. volume is indexed (M, N, P) and verts come in that axis order (z, y, x for a
    [z, y, x] volume), times spacing, given in the same order. A sample is inside when it is
    greater than level (skimage's rule: one equal to level is outside). level defaults to the
    midpoint of the data range and must lie within it. gradient_direction "descent" (the
    object is greater than its exterior) or "ascent" only reverses the faces' winding; the
    normals point toward lower values either way, as skimage's do. step_size n meshes every
    n-th sample along each axis. values: for each vertex, the largest spread (maximum minus
    minimum sample) of the cells its triangles lie in. mask: a cell is meshed when mask is
    True at its far corner (its +1, +1, +1 sample), which is where skimage looks.
    allow_degenerate=False merges vertices that coincide in a triangle and drops the
    triangles that had them.

    Where it differs from skimage:
    - Vertex order (and so the numbers in faces and the rows of normals and values): the
      same vertex set, one per crossed edge, in voxmesh's canonical order.
    - The triangles are voxmesh's table (VTK's, the classic Lorensen-Cline one): for
      method="lorensen" the same triangles with the same winding as skimage's. method
      "lewiner" gives that mesh too; skimage's Lewiner tables resolve ambiguous cells by the
      trilinear interpolant and may triangulate them differently, with an extra vertex
      inside the cell. Ours is still closed and crack-free: a face two cells share is cut
      the same way in both.
    - normals are the field's gradient (central differences, in sample units as skimage's
      are, so spacing does not change them) at the vertex; skimage sums corner differences
      of the (masked-in) cells around it. They agree closely on smooth fields, not bit for
      bit, least at a mask's edge.
    - allow_degenerate=False merges each group of coincident vertices into one, the first
      in our order (its normal and value stay); skimage, merging face by face, sometimes
      keeps a second copy of such a point. The triangles left are the same.
    - A NaN or infinite sample is refused (ValueError) rather than meshed into garbage, and
      method="_lorensen" (skimage's deprecated older implementation) is not offered.

    Bad arguments raise ValueError with skimage's message (level outside the data range,
    not 3-D, under 2x2x2, spacing, step_size, mask shape, method, gradient_direction); no
    surface (level at the data's maximum, or everything masked out) raises RuntimeError, as
    skimage does. A NaN level is a ValueError here (skimage: RuntimeError, no surface).
    """
    if method not in _METHODS:
        raise ValueError("method should be either 'lewiner' or 'lorensen'")
    if gradient_direction not in ("descent", "ascent"):
        raise ValueError(f"Incorrect input {gradient_direction} in `gradient_direction`, see docstring.")
    if backend not in _BACKENDS:
        raise ValueError(f"unknown backend {backend!r} (auto, cpu, opencl, hybrid)")
    volume = np.asarray(volume)
    if volume.ndim != 3:
        raise ValueError("Input volume should be a 3D numpy array.")
    if min(volume.shape) < 2:
        raise ValueError("Input array must be at least 2x2x2.")
    if volume.dtype == np.bool_:
        volume = volume.view(np.uint8)
    if volume.dtype.type not in _EXACT_IN_FLOAT32 or not volume.dtype.isnative:
        volume = volume.astype(np.float32)  # what skimage meshes: the float32 values
    given = None if level is None else float(level)
    # One pass for the range and, when level is known, the samples exactly at it (see below).
    counted = given is not None and step_size == 1  # else data, the samples meshed, is known only later
    if step_size == 1:  # one copy where the layout needs one, shared with `data` below
        volume = np.require(volume, requirements=["C", "A"])
    summary = _value_range(volume, given if counted else None, threads)
    if summary.nonfinite:
        raise ValueError("volume holds NaN or infinite samples")
    low, high = np.float32(summary.min), np.float32(summary.max)
    if level is None:
        level = 0.5 * (low + high)
    level = float(level)
    if not low <= level <= high:  # NaN fails too
        raise ValueError("Surface level must be within volume data range.")
    if len(spacing) != 3:
        raise ValueError("`spacing` must consist of three floats.")
    step = int(step_size)
    if step < 1:
        raise ValueError("step_size must be at least one.")
    if mask is not None:
        mask = np.asarray(mask)
        if mask.shape != volume.shape:
            raise ValueError("volume and mask must have the same shape.")
        # skimage tests the mask at each cell's far corner (see the docstring).
        mask = np.asarray(mask[step::step, step::step, step::step], dtype=bool)  # no copy of a bool mask

    data = volume[::step, ::step, ::step]
    if min(data.shape) < 2:
        raise RuntimeError(_NO_SURFACE)  # a step past the volume leaves no cell, as in skimage
    corner = np.zeros(3, dtype=np.int64)  # data's first sample in the stepped volume, (x, y, z)
    if mask is not None:
        data, mask, corner = _crop_to_mask(data, mask)
    data = np.ascontiguousarray(data)
    # voxmesh's inside is value >= iso; only a sample exactly at level tells that from
    # skimage's value > level. Nudged one float below level it is outside, and its edges'
    # vertices, a hair off the sample, are put back on it below.
    at_level_count = summary.equal if counted else _value_range(data, level, threads).equal
    at_level = _equal(data, level) if at_level_count else None
    meshed = data
    if at_level is not None:
        meshed = data.astype(np.float32)
        meshed[at_level] = np.nextafter(np.float32(level), np.float32(-np.inf))
    # spacing = step: positions come out as skimage's, index * step + t * step, rounded once.
    mesh = _as_skimage_errors(extract, meshed, iso=level, spacing=(step, step, step), origin=tuple(corner * step),
                              threads=threads, backend=backend)
    if mesh.triangle_count == 0:
        raise RuntimeError(_NO_SURFACE)
    positions = np.array(mesh.positions[:, ::-1])  # x, y, z -> array axis order
    normals = np.array(mesh.normals[:, ::-1])
    faces = mesh.indices  # uint32, converted once at the end (it keeps the mesh's memory until then)
    del mesh

    # The canonical order ties vertex i to the i-th crossed edge of what extract meshed.
    edges = _as_skimage_errors(vertex_edges, meshed, level, threads=threads, count=len(positions))
    if at_level is not None:
        owner, axis = np.divmod(edges.astype(np.int64), 3)
        _snap_to_samples(positions, data, level, owner, axis, step, corner)
    if mask is not None:  # the triangles of the kept cells (np.compress: a boolean index is slower)
        kept = mask.ravel()[_as_skimage_errors(triangle_cells, meshed, level, threads=threads, count=len(faces))]
        faces = np.compress(kept, faces, axis=0)
    if len(faces) == 0:
        raise RuntimeError(_NO_SURFACE)
    # skimage's values: per vertex, the largest (max - level) - (min - level) over the
    # (masked-in) cells around its edge, every one of which uses the vertex.
    values = _as_skimage_errors(edge_cell_ranges, data, edges, offset=level, cell_mask=mask, threads=threads)
    if mask is not None:
        # Vertices of the dropped cells only go, keeping the others' order. A vertex is used
        # when a kept cell is around its edge (a cell's triangles use every crossed edge it
        # has), which is where its value is not 0: the range of a cell an edge crosses is not.
        used = values > 0
        renumber = np.cumsum(used, dtype=np.int32) - 1  # int32: skimage's type for faces
        faces = renumber[faces]
        positions, normals, values = (np.compress(used, a, axis=0) for a in (positions, normals, values))

    if gradient_direction == "ascent":
        faces = faces[:, ::-1]
    faces = np.ascontiguousarray(faces, dtype=np.int32)  # skimage's type
    verts = positions
    if not np.array_equal(spacing, (1, 1, 1)):
        verts = positions * np.asarray(spacing)  # float64, as in skimage
    if allow_degenerate:
        return verts, faces, normals, values
    return _without_degenerate(verts.astype(np.float32), faces, normals, values)


def _as_skimage_errors(call, *args, **kwargs):
    """call(*args, **kwargs), a VoxmeshError from it raised as skimage's ValueError (running out
    of memory stays a MemoryError)."""
    try:
        return call(*args, **kwargs)
    except VoxmeshError as error:
        if isinstance(error, MemoryError):
            raise
        raise ValueError(str(error)) from error


def _value_range(volume, equal_to, threads):
    return _as_skimage_errors(value_range, volume, equal_to=equal_to, threads=threads)


def _equal(data, level):
    """Where data == level exactly, or None where no sample is (the usual case)."""
    if data.dtype.kind in "iu":
        if level != int(level):
            return None
        found = data == int(level)
    else:
        if level != float(np.float32(level)):
            return None
        found = data == np.float32(level)
    return found if found.any() else None


def _coordinates(owner, shape):
    nz, ny, nx = shape
    return np.stack([owner % nx, owner // nx % ny, owner // (nx * ny)])  # x, y, z


def _crop_to_mask(data, mask):
    """data cut to the box of the cells mask keeps, with one sample more on each side where
    data has one, so that the gradients at those cells' corners are the uncut volume's; the
    mask cut to match, and the cut's first sample as (x, y, z). Meshing the cut gives the
    same kept triangles and vertices in the same order (the canonical order is by position)
    without meshing what the mask drops. Nothing kept raises skimage's RuntimeError."""
    # Two passes over the mask, not one per axis: the rows that keep a cell give the first two
    # axes' spans, and the last axis' comes from a reduction numpy runs fast on a strided mask.
    rows = mask.any(axis=2)
    spans = []
    for axis, kept in enumerate((rows.any(axis=1), rows.any(axis=0), mask.any(axis=(0, 1)))):
        kept = np.flatnonzero(kept)
        if len(kept) == 0:
            raise RuntimeError(_NO_SURFACE)
        spans.append((max(int(kept[0]) - 1, 0), min(int(kept[-1]) + 3, data.shape[axis])))
    samples = tuple(slice(begin, end) for begin, end in spans)
    cells = tuple(slice(begin, end - 1) for begin, end in spans)
    corner = np.array([begin for begin, _ in spans[::-1]], dtype=np.int64)
    return data[samples], np.ascontiguousarray(mask[cells]), corner  # the mask once, for both its uses


def _snap_to_samples(positions, data, level, owner, axis, step, corner):
    """Vertices of edges with an end exactly at level go onto that sample, where skimage puts
    them (so that allow_degenerate=False finds them coincident). Except from an array's first
    plane: skimage's weights (1 / (2.2e-16 + |v - level|) at each end) leave such a vertex
    about 1e-16 off index 0, which float32 keeps, so there it is not coincident, and neither
    is ours."""
    flat = data.ravel()
    strides = np.array([1, data.shape[2], data.shape[1] * data.shape[2]])
    for end in (0, 1):
        far = flat[owner + strides[axis]].astype(np.float64)
        hit = np.flatnonzero((far if end else flat[owner].astype(np.float64)) == level)
        if len(hit):
            xyz = _coordinates(owner[hit], data.shape) + corner[:, None]  # in the stepped volume
            column = 2 - axis[hit]  # the edge's axis among positions' z, y, x
            rows = np.arange(len(hit))
            first = (xyz[axis[hit], rows] == 0) if end == 0 else np.zeros(len(hit), dtype=bool)
            xyz[axis[hit], rows] += end
            positions[hit] = (xyz[::-1].T * step).astype(np.float32)
            if first.any():
                epsilon = np.finfo(np.float64).eps
                weight = 1.0 / (epsilon + np.abs(far[hit[first]] - level))
                positions[hit[first], column[first]] = (step * (weight / (1.0 / epsilon + weight))).astype(np.float32)


def _without_degenerate(verts, faces, normals, values):
    """Triangles with two coincident corners go; their coincident corners become one vertex
    (the lowest numbered), which the other triangles then use. Other vertices stay."""
    a, b, c = (verts[faces[:, k]] for k in range(3))
    same = [np.all(a == b, axis=1), np.all(b == c, axis=1), np.all(a == c, axis=1)]
    pairs = np.concatenate([faces[same[0]][:, [0, 1]], faces[same[1]][:, [1, 2]], faces[same[2]][:, [0, 2]]])
    target = np.arange(len(verts))
    while len(pairs):  # lowest number over each group of coincident vertices
        low = np.minimum(target[pairs[:, 0]], target[pairs[:, 1]])
        changed = (target[pairs[:, 0]] != low) | (target[pairs[:, 1]] != low)
        if not changed.any():
            break
        np.minimum.at(target, pairs[:, 0], low)
        np.minimum.at(target, pairs[:, 1], low)
        target = target[target]
    kept = target == np.arange(len(verts))
    renumber = np.cumsum(kept) - 1
    faces = renumber[target[faces[~(same[0] | same[1] | same[2])]]]  # int64, as skimage's
    return verts[kept], faces, normals[kept], values[kept]
