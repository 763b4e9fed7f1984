"""voxmesh.marching_cubes, the drop-in for skimage.measure.marching_cubes: first against what
its results must be on their own (no scikit-image needed), then against scikit-image itself
where it is installed (Debian's python3-skimage). Run by ctest with PYTHONPATH at the build's
python/ folder; exits 77 (skipped) where numpy is missing, except under CI."""

import os
import sys
import unittest

try:
    import numpy as np
except ImportError:
    if os.environ.get("CI"):
        raise
    print("numpy is missing: install python3-numpy (scripts/install-deps.sh does)")
    sys.exit(77)

import voxmesh

try:
    from skimage import measure
except ImportError:
    measure = None


def sphere(shape, radius, center, dtype=np.float32):
    """radius - distance to center (z, y, x): positive inside, indexed [z, y, x]."""
    z, y, x = np.mgrid[:shape[0], :shape[1], :shape[2]]
    cz, cy, cx = center
    return (radius - np.sqrt((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2)).astype(dtype)


def gyroid(n, scale=0.45):
    z, y, x = np.mgrid[:n, :n, :n] * scale
    return (np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)).astype(np.float32)


def signed_volume(verts, faces):
    p = np.asarray(verts, dtype=np.float64)[faces]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0


def triangles(verts, faces):
    """Each triangle as its corners' positions, turned to start at the smallest (so that the
    same triangle with the same winding is the same tuple), counted."""
    found = {}
    for corners in np.round(np.asarray(verts, dtype=np.float64), 4)[faces]:
        corners = [tuple(c) for c in corners]
        key = min(tuple(corners[k:] + corners[:k]) for k in range(3))
        found[key] = found.get(key, 0) + 1
    return found


SPHERE = sphere((36, 40, 44), 13.0, (17.3, 19.6, 21.2))


class OwnTest(unittest.TestCase):
    """What the results must be, from voxmesh's own mesh and the volume."""

    def test_verts_faces_normals_are_extracts_in_array_axis_order(self):
        mesh = voxmesh.extract(SPHERE, iso=0.0)
        verts, faces, normals, values = voxmesh.marching_cubes(SPHERE, 0.0, spacing=(3.0, 2.0, 0.5))
        np.testing.assert_array_equal(verts, mesh.positions[:, ::-1] * np.array([3.0, 2.0, 0.5]))
        np.testing.assert_array_equal(faces, mesh.indices)
        np.testing.assert_array_equal(normals, mesh.normals[:, ::-1])
        self.assertEqual(values.shape, (len(verts),))

    def test_types_and_shapes_are_skimages(self):
        verts, faces, normals, values = voxmesh.marching_cubes(SPHERE, 0.0)
        self.assertEqual((verts.dtype, faces.dtype, normals.dtype, values.dtype),
                         (np.float32, np.int32, np.float32, np.float32))
        self.assertEqual((verts.shape[1], faces.shape[1], normals.shape, values.shape),
                         (3, 3, verts.shape, (len(verts),)))
        self.assertEqual(voxmesh.marching_cubes(SPHERE, 0.0, spacing=(1, 2, 1))[0].dtype, np.float64)
        verts, faces, _, _ = voxmesh.marching_cubes(SPHERE, 0.0, spacing=(1, 2, 1), allow_degenerate=False)
        self.assertEqual((verts.dtype, faces.dtype), (np.float32, np.int64))

    def test_descent_and_ascent_wind_oppositely_and_normals_point_down_the_field(self):
        r = 13.0
        center = np.array([17.3, 19.6, 21.2])
        for direction, sign in (("descent", 1), ("ascent", -1)):
            verts, faces, normals, _ = voxmesh.marching_cubes(SPHERE, 0.0, gradient_direction=direction)
            # Seen in x, y, z order (verts reversed) descent winds counter-clockwise seen from
            # outside, enclosing a positive volume; in the array's z, y, x order the sign flips
            # (skimage's "left-hand rule").
            ratio = signed_volume(verts[:, ::-1], faces) / (4 / 3 * np.pi * r ** 3)
            self.assertAlmostEqual(sign * ratio, 1.0, delta=0.01)
            self.assertLess(sign * signed_volume(verts, faces), 0)
            # Normals: unit, toward lower values (away from the center) for both directions.
            np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
            self.assertTrue(np.all(np.einsum("ij,ij->i", normals, verts - center) > 0))

    def test_normals_ignore_spacing_as_skimages_do(self):
        plain = voxmesh.marching_cubes(SPHERE, 0.0)[2]
        stretched = voxmesh.marching_cubes(SPHERE, 0.0, spacing=(1.0, 4.0, 0.25))[2]
        np.testing.assert_allclose(stretched, plain, atol=1e-6)

    def test_default_level_is_the_middle_of_the_data_range(self):
        volume = SPHERE * 3 + 7
        middle = 0.5 * (float(volume.min()) + float(volume.max()))
        for got, want in zip(voxmesh.marching_cubes(volume), voxmesh.marching_cubes(volume, middle)):
            np.testing.assert_array_equal(got, want)

    def test_lewiner_and_lorensen_give_the_same_mesh(self):
        volume = gyroid(24)
        for got, want in zip(voxmesh.marching_cubes(volume, 0.2, method="lewiner"),
                             voxmesh.marching_cubes(volume, 0.2, method="lorensen")):
            np.testing.assert_array_equal(got, want)

    def test_values_are_the_largest_spread_of_the_cells_around_each_vertex(self):
        rng = np.random.default_rng(7)
        volume = rng.standard_normal((6, 7, 8)).astype(np.float32)
        level = 0.1
        verts, faces, _, values = voxmesh.marching_cubes(volume, level)
        for vertex, value in zip(verts, values):
            # The edge is along the one axis where the vertex is between samples.
            whole = np.floor(vertex).astype(int)
            along = np.flatnonzero(vertex != whole)
            self.assertEqual(len(along), 1)
            spreads = []
            for d0 in (0, -1):
                for d1 in (0, -1):
                    corner = whole.copy()
                    corner[[a for a in range(3) if a != along[0]]] += (d0, d1)
                    if np.all(corner >= 0) and np.all(corner <= np.array(volume.shape) - 2):
                        cell = volume[corner[0]:corner[0] + 2, corner[1]:corner[1] + 2, corner[2]:corner[2] + 2]
                        spreads.append(np.float32(float(cell.max()) - float(cell.min())))
            self.assertEqual(value, max(spreads))

    def test_step_size_meshes_every_nth_sample(self):
        for step in (2, 3):
            coarse = SPHERE[::step, ::step, ::step]
            got = voxmesh.marching_cubes(SPHERE, 0.0, step_size=step)
            want = voxmesh.marching_cubes(coarse, 0.0)
            np.testing.assert_allclose(got[0], want[0] * step, rtol=0, atol=1e-5)
            np.testing.assert_array_equal(got[1], want[1])
            np.testing.assert_allclose(got[2], want[2], atol=1e-6)
            np.testing.assert_array_equal(got[3], want[3])

    def test_a_sample_at_level_is_outside(self):
        volume = np.zeros((5, 5, 5), dtype=np.uint8)
        volume[2, 2, 2] = 1
        verts, faces, _, _ = voxmesh.marching_cubes(volume, 0)
        # An octahedron on the six neighbours (inside would be value >= level: everything).
        want = {(1, 2, 2), (3, 2, 2), (2, 1, 2), (2, 3, 2), (2, 2, 1), (2, 2, 3)}
        self.assertEqual({tuple(v) for v in verts.astype(int)}, want)
        np.testing.assert_array_equal(verts, np.round(verts))
        self.assertEqual(len(faces), 8)

    def test_allow_degenerate_false_removes_the_zero_area_triangles(self):
        # Integer samples and an integer level: many vertices land exactly on samples.
        volume = np.round(sphere((20, 20, 20), 7.0, (9.5, 9.2, 9.7)) * 2).astype(np.int16)
        verts, faces, normals, values = voxmesh.marching_cubes(volume, 2)
        corners = verts[faces]
        coincide = (np.all(corners[:, 0] == corners[:, 1], axis=1) | np.all(corners[:, 1] == corners[:, 2], axis=1)
                    | np.all(corners[:, 0] == corners[:, 2], axis=1))
        self.assertGreater(coincide.sum(), 0)
        kept_verts, kept_faces, kept_normals, kept_values = voxmesh.marching_cubes(volume, 2, allow_degenerate=False)
        corners = kept_verts[kept_faces]
        self.assertFalse(np.any(np.all(corners[:, 0] == corners[:, 1], axis=1)))
        self.assertFalse(np.any(np.all(corners[:, 1] == corners[:, 2], axis=1)))
        self.assertFalse(np.any(np.all(corners[:, 0] == corners[:, 2], axis=1)))
        self.assertEqual(triangles(kept_verts, kept_faces), triangles(verts, faces[~coincide]))
        # Only copies of a point go: the same points, now each once where triangles met.
        self.assertEqual({tuple(v) for v in kept_verts}, {tuple(v) for v in verts})
        self.assertLess(len(kept_verts), len(verts))
        self.assertEqual((len(kept_normals), len(kept_values)), (len(kept_verts), len(kept_verts)))

    def test_mask_meshes_the_cells_whose_far_corner_it_holds(self):
        full = voxmesh.marching_cubes(SPHERE, 0.0)
        everywhere = voxmesh.marching_cubes(SPHERE, 0.0, mask=np.ones(SPHERE.shape, dtype=bool))
        for got, want in zip(everywhere, full):
            np.testing.assert_array_equal(got, want)
        mask = np.zeros(SPHERE.shape, dtype=bool)
        mask[:, :, :22] = True  # far corners x <= 21: cells x <= 20
        verts, faces, normals, values = voxmesh.marching_cubes(SPHERE, 0.0, mask=mask)
        self.assertLessEqual(verts[:, 2].max(), 21.0)
        self.assertEqual(len(np.unique(faces)), len(verts))  # no vertex left unused
        kept = triangles(verts, faces)
        whole = triangles(*full[:2])
        self.assertTrue(all(key in whole for key in kept))
        centroid_x = full[0][full[1]][:, :, 2].mean(axis=1)
        self.assertEqual(len(kept), len(triangles(full[0], full[1][centroid_x < 20.999])))
        with self.assertRaises(RuntimeError):
            voxmesh.marching_cubes(SPHERE, 0.0, mask=np.zeros(SPHERE.shape, dtype=bool))

    def test_a_mask_gives_the_whole_meshs_triangles_of_its_cells(self):
        # The drop-in meshes only the box of the cells a mask keeps (and a sample around it);
        # the result must be, bit for bit, the whole volume's mesh cut down to those cells:
        # extract's triangles of the kept cells (triangle_cells), the vertices they use in
        # their order, and values over the kept cells alone.
        rng = np.random.default_rng(3)
        gyr = gyroid(30, 0.5) + np.float32(0.013)  # no sample exactly at the level
        for volume in (SPHERE, gyr):
            shape = volume.shape
            boxes = [(slice(6, 30), slice(9, 27), slice(4, 20)), (slice(None), slice(None), slice(0, 22)),
                     (slice(1, 3), slice(2, shape[1]), slice(shape[2] - 5, shape[2]))]
            for box in boxes:
                mask = np.zeros(shape, dtype=bool)
                mask[box] = rng.random(mask[box].shape) < 0.8
                cells = mask[1:, 1:, 1:]  # a cell is kept by its far corner
                mesh = voxmesh.extract(volume, 0.0, threads=1)
                kept = cells.ravel()[voxmesh.triangle_cells(volume, 0.0)]
                if not kept.any():
                    continue
                faces = mesh.indices[kept]
                used = np.zeros(mesh.vertex_count, dtype=bool)
                used[faces.ravel()] = True
                edges = voxmesh.vertex_edges(volume, 0.0)
                want = (mesh.positions[used][:, ::-1], (np.cumsum(used) - 1)[faces], mesh.normals[used][:, ::-1],
                        voxmesh.edge_cell_ranges(volume, edges, 0.0, cells)[used])
                got = voxmesh.marching_cubes(volume, 0.0, mask=mask, threads=2)
                for name, g, w in zip(("verts", "faces", "normals", "values"), got, want):
                    with self.subTest(box=box, result=name):
                        np.testing.assert_array_equal(g, w)

    def test_sample_types_give_the_float32_mesh(self):
        volume = np.clip(SPHERE * 20 + 128, 0, 255).astype(np.uint8)
        for level in (127.5, 128):
            want = voxmesh.marching_cubes(volume.astype(np.float32), level)
            for kind in (np.uint8, np.int16, np.int32, np.float64):
                for got, expected in zip(voxmesh.marching_cubes(volume.astype(kind), level), want):
                    np.testing.assert_array_equal(got, expected)

    def test_bad_arguments_raise_value_error_naming_the_problem(self):
        # Found by a review: the README said the errors were scikit-image's; the messages were
        # our own. Now they are skimage's (0.26) word for word where it has one.
        cases = [
            (dict(level=100.0), "Surface level must be within volume data range."),
            (dict(volume=SPHERE[0]), "Input volume should be a 3D numpy array."),
            (dict(volume=SPHERE[:1]), "Input array must be at least 2x2x2."),
            (dict(gradient_direction="up"), "Incorrect input up in `gradient_direction`, see docstring."),
            (dict(method="_lorensen"), "method should be either 'lewiner' or 'lorensen'"),
            (dict(method="marching"), "method should be either 'lewiner' or 'lorensen'"),
            (dict(step_size=0), "step_size must be at least one."),
            (dict(spacing=(1.0, 2.0)), "`spacing` must consist of three floats."),
            (dict(mask=np.ones((3, 3, 3), dtype=bool)), "volume and mask must have the same shape."),
            (dict(backend="gpu"), "unknown backend 'gpu'"),
            (dict(level=float("nan")), "Surface level must be within volume data range."),
        ]
        for change, message in cases:
            arguments = dict(volume=SPHERE, level=0.0) | change
            with self.subTest(change=change):
                with self.assertRaises(ValueError) as raised:
                    voxmesh.marching_cubes(arguments.pop("volume"), arguments.pop("level"), **arguments)
                self.assertTrue(str(raised.exception).startswith(message), str(raised.exception))
        holed = SPHERE.copy()
        holed[3, 4, 5] = np.nan
        with self.assertRaisesRegex(ValueError, "NaN"):
            voxmesh.marching_cubes(holed, 0.0)

    def test_no_surface_raises_runtime_error(self):
        with self.assertRaisesRegex(RuntimeError, "No surface"):
            voxmesh.marching_cubes(SPHERE, float(SPHERE.max()))  # nothing is above the maximum
        with self.assertRaisesRegex(RuntimeError, "No surface"):
            voxmesh.marching_cubes(SPHERE, 0.0, step_size=50)  # not one cell left


@unittest.skipIf(measure is None, "scikit-image is not installed (python3-skimage)")
class ScikitImageTest(unittest.TestCase):
    """Against skimage.measure.marching_cubes: the same vertices (in another order), the same
    triangles with the same winding, the same values and types, close normals."""

    def compare(self, volume, level, normals_at_least=0.99, same_triangles=True, **options):
        theirs = measure.marching_cubes(volume, level, **options)
        ours = voxmesh.marching_cubes(volume, level, **options)
        self.assertEqual([a.dtype for a in ours], [a.dtype for a in theirs])
        self.assertEqual([a.shape for a in ours], [a.shape for a in theirs])
        # Vertices sorted by position (ties by value): then row for row the same vertex.
        order_ours = np.lexsort(np.c_[ours[3], ours[0]].T)
        order_theirs = np.lexsort(np.c_[theirs[3], theirs[0]].T)
        np.testing.assert_allclose(ours[0][order_ours], theirs[0][order_theirs], rtol=0, atol=1e-4)
        np.testing.assert_array_equal(ours[3][order_ours], theirs[3][order_theirs])
        if same_triangles:
            self.assertEqual(triangles(*ours[:2]), triangles(*theirs[:2]))
        # Normals: gradient at the vertex here, summed corner differences of the cells there.
        dots = np.einsum("ij,ij->i", ours[2][order_ours], theirs[2][order_theirs])
        self.assertGreater(dots.min(), normals_at_least)
        self.assertGreater(dots.mean(), 0.995)
        return ours, theirs

    def test_sphere(self):
        self.compare(SPHERE, 0.0)
        self.compare(SPHERE, 0.0, method="lorensen")

    def test_sphere_anisotropic_spacing(self):
        self.compare(SPHERE, 0.0, spacing=(1.0, 2.0, 0.5))

    def test_sphere_ascent(self):
        self.compare(SPHERE, 0.0, gradient_direction="ascent", spacing=(2.0, 1.0, 1.0))

    def test_sphere_step_size(self):
        self.compare(SPHERE, 0.0, step_size=2)
        self.compare(SPHERE, 0.0, step_size=3, spacing=(0.5, 0.5, 2.0))

    def test_sphere_mask(self):
        mask = np.zeros(SPHERE.shape, dtype=bool)
        mask[:, 10:30, :22] = True
        self.compare(SPHERE, 0.0, mask=mask, normals_at_least=0.95)
        self.compare(SPHERE, 0.0, mask=mask, step_size=2, normals_at_least=0.95)

    def test_gyroid(self):
        volume = gyroid(40)
        # Lorensen's table is ours: the same triangles. Lewiner's resolves ambiguous cells by
        # the trilinear interpolant instead, so there only the vertices and values must agree.
        self.compare(volume, 0.1, method="lorensen", normals_at_least=0.9)
        ours, theirs = self.compare(volume, 0.1, method="lewiner", normals_at_least=0.9, same_triangles=False)
        common = set(triangles(*ours[:2])) & set(triangles(*theirs[:2]))
        self.assertGreater(len(common), 0.99 * len(ours[1]))

    def test_uint8(self):
        volume = np.clip(SPHERE * 20 + 128, 0, 255).astype(np.uint8)
        self.compare(volume, 127.5)
        self.compare(volume, None)  # the middle of 0..255, as skimage computes it
        self.compare(volume, 128, method="lorensen", normals_at_least=0.95)  # samples at the level

    def test_the_same_errors(self):
        # Found by a review: the README said the errors were scikit-image's; the messages differed.
        # (An unknown method's message is 0.26's: older versions also offered "_lorensen".)
        cases = [dict(level=100.0), dict(level=-100.0), dict(volume=SPHERE[0]), dict(volume=SPHERE[:1]),
                 dict(step_size=0), dict(spacing=(1.0, 2.0)),
                 dict(mask=np.ones((3, 3, 3), dtype=bool)), dict(level=float(SPHERE.max())),
                 dict(gradient_direction="up")]
        for change in cases:
            arguments = dict(volume=SPHERE, level=0.0) | change
            found = []
            for call in (measure.marching_cubes, voxmesh.marching_cubes):
                try:
                    call(arguments["volume"], arguments["level"],
                         **{k: v for k, v in arguments.items() if k not in ("volume", "level")})
                    found.append(None)
                except (ValueError, RuntimeError) as error:
                    found.append((type(error), str(error)))
            with self.subTest(change=change):
                self.assertEqual(found[0], found[1])

    def test_allow_degenerate_false(self):
        volume = np.clip(SPHERE * 20 + 128, 0, 255).astype(np.uint8)
        theirs = measure.marching_cubes(volume, 128, allow_degenerate=False)
        ours = voxmesh.marching_cubes(volume, 128, allow_degenerate=False)
        self.assertEqual([a.dtype for a in ours], [a.dtype for a in theirs])
        self.assertEqual(triangles(*ours[:2]), triangles(*theirs[:2]))
        # Which copy of a point survives follows the vertex order, so compare the points.
        self.assertEqual({tuple(v) for v in ours[0]}, {tuple(v) for v in theirs[0]})
        self.assertEqual(len(ours[0]), len(theirs[0]))


if __name__ == "__main__":
    unittest.main(verbosity=2)
