// VolumeInfo's world transform and to_world: a volume whose direction matrix is not diagonal
// (an axis permutation, a rotation, with and without flipped axes) meshes into the place the
// file's affine gives, with outward normals, still closed.
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>

#include "support/io_scratch.hpp"
#include "support/mesh_checks.hpp"

using namespace voxmesh;

namespace {

using iotest::Scratch;
using Vec = std::array<double, 3>;
using Dims = std::array<std::size_t, 3>;
constexpr double kPi = 3.14159265358979323846;

// What a file says: file sample f lies at origin + sum over a of step[a] * f[a].
struct Affine {
    Vec origin{};
    std::array<Vec, 3> step{};  // index axis a's step in world components (direction * spacing)
    Vec at(const Vec& f) const {
        Vec w = origin;
        for (std::size_t a = 0; a < 3; ++a)
            for (std::size_t c = 0; c < 3; ++c) w[c] += step[a][c] * f[a];
        return w;
    }
};

double distance(const Vec& a, const Vec& b) { return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

// Rz(z degrees) * Rx(x degrees), column a: where world axis a goes.
std::array<Vec, 3> rotation(double z_deg, double x_deg) {
    const double z = z_deg * kPi / 180, x = x_deg * kPi / 180;
    return {{{std::cos(z), std::sin(z), 0},
             {-std::sin(z) * std::cos(x), std::cos(z) * std::cos(x), std::sin(x)},
             {std::sin(z) * std::sin(x), -std::cos(z) * std::sin(x), std::cos(x)}}};
}

// Float samples of the world-space sphere (radius - distance to `centre`), in file order.
std::string sphere_samples(const Dims& n, const Affine& file, const Vec& centre, double radius) {
    std::string out;
    for (std::size_t k = 0; k < n[2]; ++k)
        for (std::size_t j = 0; j < n[1]; ++j)
            for (std::size_t i = 0; i < n[0]; ++i) {
                const float v = static_cast<float>(radius - distance(file.at({double(i), double(j), double(k)}), centre));
                char b[4];
                std::memcpy(b, &v, 4);
                out.append(b, 4);
            }
    return out;
}

std::string nrrd_file(const Dims& n, const Affine& file, const std::string& samples) {
    std::ostringstream h;  // (ostringstream: GCC 12's -Wrestrict misfires on "(" + std::string)
    h << "NRRD0004\ntype: float\ndimension: 3\nsizes: " << n[0] << " " << n[1] << " " << n[2]
      << "\nendian: little\nencoding: raw\nspace: left-posterior-superior\nspace directions:";
    h.precision(17);
    const auto vec = [&](const Vec& v) { h << "(" << v[0] << "," << v[1] << "," << v[2] << ")"; };
    for (const Vec& s : file.step) {
        h << " ";
        vec(s);
    }
    h << "\nspace origin: ";
    vec(file.origin);
    h << "\n\n";
    return h.str() + samples;
}

// A NIfTI-1 float file (little endian) with an sform (the affine) or a qform (a rotation by
// quaternion b, c, d, qfac and pixdim).
struct Nifti {
    std::string header = std::string(352, '\0');
    template <class T>
    void put(std::size_t offset, T value) {
        std::memcpy(header.data() + offset, &value, sizeof(T));
    }
    explicit Nifti(const Dims& n) {
        put<std::int32_t>(0, 348);
        const std::int16_t dim[8] = {3, std::int16_t(n[0]), std::int16_t(n[1]), std::int16_t(n[2]), 1, 1, 1, 1};
        for (std::size_t i = 0; i < 8; ++i) put<std::int16_t>(40 + 2 * i, dim[i]);
        put<std::int16_t>(70, 16);  // float32
        put<std::int16_t>(72, 32);
        for (std::size_t i = 0; i < 4; ++i) put<float>(76 + 4 * i, 1);
        put<float>(108, 352);
        std::memcpy(header.data() + 344, "n+1\0", 4);
    }
    void sform(const Affine& file) {
        put<std::int16_t>(254, 1);
        for (std::size_t row = 0; row < 3; ++row) {
            for (std::size_t a = 0; a < 3; ++a) put<float>(280 + 16 * row + 4 * a, float(file.step[a][row]));
            put<float>(280 + 16 * row + 12, float(file.origin[row]));
        }
    }
    void qform(double b, double c, double d, float qfac, const Vec& pixdim, const Vec& offset) {
        put<std::int16_t>(252, 1);
        put<float>(256, float(b));
        put<float>(260, float(c));
        put<float>(264, float(d));
        for (std::size_t a = 0; a < 3; ++a) put<float>(268 + 4 * a, float(offset[a]));
        put<float>(76, qfac);
        for (std::size_t a = 0; a < 3; ++a) put<float>(80 + 4 * a, float(pixdim[a]));
    }
};

// Every sample's loaded position (origin + index * spacing, as extract places vertices),
// through to_world, is where the file's affine puts the file sample it came from.
void check_samples_placed(const VolumeInfo& info, const Affine& file) {
    Mesh points;
    std::array<std::size_t, 3> p{};
    for (p[2] = 0; p[2] < info.dims[2]; ++p[2])
        for (p[1] = 0; p[1] < info.dims[1]; ++p[1])
            for (p[0] = 0; p[0] < info.dims[0]; ++p[0])
                for (std::size_t a = 0; a < 3; ++a)
                    points.positions.push_back(float(info.origin[a] + double(p[a]) * info.spacing[a]));
    to_world(points, info);
    std::size_t checked = 0;
    iotest::for_each_sample_of_file(info.dims, info.flipped, [&](std::size_t at, std::array<std::size_t, 3> f) {
        const Vec want = file.at({double(f[0]), double(f[1]), double(f[2])});
        const Vec got{points.positions[3 * at], points.positions[3 * at + 1], points.positions[3 * at + 2]};
        INFO("sample " << at << ": " << got[0] << " " << got[1] << " " << got[2] << " want " << want[0] << " "
                       << want[1] << " " << want[2]);
        REQUIRE(distance(got, want) < 1e-4 * (1 + distance(want, {0, 0, 0})));
        ++checked;
    });
    CHECK(checked == info.dims[0] * info.dims[1] * info.dims[2]);
}

// The sphere meshed from the loaded volume and moved by to_world: on the sphere, centred,
// outward normals, positive volume, closed and consistently wound.
void check_sphere(const std::string& path, const Vec& centre, double radius, double tolerance) {
    VolumeInfo info;
    const Volume v = read_volume(path, info);
    Mesh mesh = extract(v.view(), vmtest::cpu_options(0, 1));
    REQUIRE(mesh.triangle_count() > 100);
    to_world(mesh, info);
    Vec mean{0, 0, 0};
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
        const Vec p{mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]};
        const double r = distance(p, centre);
        INFO("vertex " << i << " at distance " << r);
        REQUIRE(std::fabs(r - radius) < tolerance);
        double dot = 0;
        for (std::size_t c = 0; c < 3; ++c) {
            dot += (p[c] - centre[c]) / r * mesh.normals[3 * i + c];
            mean[c] += p[c] / double(mesh.vertex_count());
        }
        REQUIRE(dot > 0.9);
    }
    CHECK(distance(mean, centre) < tolerance);
    const double volume = vmtest::signed_volume(mesh);
    CHECK(volume > 0);
    CHECK(volume == Approx(4.0 / 3.0 * kPi * radius * radius * radius).epsilon(0.05));
    CHECK(vmtest::max_normal_length_error(mesh) < 1e-5);
    const vmtest::Topology topo = vmtest::topology(mesh);
    CHECK(topo.closed());
    CHECK(topo.consistently_oriented());
}

}  // namespace

TEST_CASE("world: NRRD with permuted space directions (determinant -1)", "[world][nrrd]") {
    Scratch s;
    const Dims n{12, 16, 20};
    Affine file;
    file.origin = {5, -3, 7};
    file.step = {{{0, 0, 2}, {1.5, 0, 0}, {0, -1, 0}}};
    const Vec centre = file.at({5.5, 7.5, 9.5});
    const std::string path = s.file("perm.nrrd", nrrd_file(n, file, sphere_samples(n, file, centre, 7)));
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.rotation_dropped);
    CHECK(info.flipped == std::array<bool, 3>{false, false, false});  // a permutation is never flipped
    CHECK(info.directions == std::array<double, 9>{0, 1, 0, 0, 0, -1, 1, 0, 0});
    CHECK(info.world_origin == file.origin);
    CHECK(has_world_transform(info));
    check_samples_placed(info, file);
    check_sphere(path, centre, 7, 0.2);
}

TEST_CASE("world: NIfTI with a rotated sform, one axis flipped", "[world][nifti]") {
    Scratch s;
    const Dims n{16, 16, 14};
    const auto r = rotation(30, 10);
    Affine file;
    file.origin = {-20, 40, 5};
    const Vec spacing{-2, 2, 2.5};  // x runs the negative way: flipped on load
    for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t c = 0; c < 3; ++c) file.step[a][c] = float(r[a][c] * spacing[a]);  // as stored
    const Vec centre = file.at({7.5, 7.5, 6.5});
    Nifti nii(n);
    nii.sform(file);
    const std::string path = s.file("rot.nii", nii.header + sphere_samples(n, file, centre, 9));
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.rotation_dropped);
    CHECK(info.flipped == std::array<bool, 3>{true, false, false});
    check_samples_placed(info, file);
    check_sphere(path, centre, 9, 0.25);
}

TEST_CASE("world: NIfTI with a rotated qform, qfac -1 flipping z", "[world][nifti]") {
    Scratch s;
    const Dims n{16, 14, 16};
    // Rz(30) * Rx(10) as a quaternion: (cos15 cos5, cos15 sin5, sin15 sin5, cos5 sin15).
    const double h = 15 * kPi / 180, g = 5 * kPi / 180;
    const Vec pixdim{2, 2.5, 2};
    const auto r = rotation(30, 10);
    Affine file;
    file.origin = {3, -7, 11};
    for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t c = 0; c < 3; ++c) file.step[a][c] = r[a][c] * pixdim[a] * (a == 2 ? -1 : 1);
    const Vec centre = file.at({7.5, 6.5, 7.5});
    Nifti nii(n);
    nii.qform(std::cos(h) * std::sin(g), std::sin(h) * std::sin(g), std::cos(g) * std::sin(h), -1, pixdim, file.origin);
    const std::string path = s.file("q.nii", nii.header + sphere_samples(n, file, centre, 9));
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.rotation_dropped);
    CHECK(info.flipped == std::array<bool, 3>{false, false, true});
    check_samples_placed(info, file);
    check_sphere(path, centre, 9, 0.25);
}

TEST_CASE("world: flips only leave the transform the identity", "[world][nrrd]") {
    Scratch s;
    const Dims n{12, 10, 14};
    Affine file;
    file.origin = {10, 20, 30};
    file.step = {{{-2, 0, 0}, {0, 1.5, 0}, {0, 0, -1}}};
    const std::string path = s.file("flip.nrrd", nrrd_file(n, file, sphere_samples(n, file, file.at({5.5, 4.5, 6.5}), 5)));
    VolumeInfo info;
    const Volume v = read_volume(path, info);
    CHECK_FALSE(info.rotation_dropped);
    CHECK(info.directions == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1});
    CHECK(info.world_origin == info.origin);
    CHECK_FALSE(has_world_transform(info));
    check_samples_placed(info, file);
    const Mesh mesh = extract(v.view(), vmtest::cpu_options(0, 1));
    Mesh moved = mesh;
    to_world(moved, info);
    CHECK(vmtest::same_bits(moved.positions, mesh.positions));
    CHECK(vmtest::same_bits(moved.normals, mesh.normals));
    CHECK(moved.indices == mesh.indices);
}

TEST_CASE("world: to_world under a mirroring keeps normals outward and reverses winding", "[world]") {
    const Mesh mesh = vmtest::small_sphere_mesh(true);
    REQUIRE(vmtest::signed_volume(mesh) > 0);
    VolumeInfo info;  // a reflection through the plane x = y, then a shift
    info.directions = {0, 1, 0, 1, 0, 0, 0, 0, 1};
    info.world_origin = {100, 0, -50};
    Mesh moved = mesh;
    to_world(moved, info);
    CHECK(vmtest::signed_volume(moved) == Approx(vmtest::signed_volume(mesh)).epsilon(1e-4));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
        CHECK(moved.positions[3 * i] == Approx(100 + mesh.positions[3 * i + 1]));
        CHECK(moved.positions[3 * i + 1] == Approx(mesh.positions[3 * i]));
        CHECK(moved.normals[3 * i] == Approx(mesh.normals[3 * i + 1]).margin(1e-6));
        CHECK(moved.normals[3 * i + 1] == Approx(mesh.normals[3 * i]).margin(1e-6));
    }
    CHECK(vmtest::topology(moved).consistently_oriented());

    Mesh bad = mesh;
    info.directions = {1, 0, 0, 1, 0, 0, 0, 0, 1};  // singular
    CHECK_THROWS_AS(to_world(bad, info), Error);
    bad.normals.pop_back();
    info.directions = {0, 1, 0, 1, 0, 0, 0, 0, 1};
    CHECK_THROWS_AS(to_world(bad, info), Error);
}

TEST_CASE("world: MetaImage with a rotated TransformMatrix and a negative spacing", "[world][metaimage]") {
    Scratch s;
    const Dims n{14, 16, 12};
    const auto r = rotation(20, 0);
    const Vec spacing{1.5, -2, 2.5};  // y runs against its direction: flipped on load
    Affine file;
    file.origin = {4, 5, 6};
    std::ostringstream head;
    head.precision(17);
    head << "ObjectType = Image\nNDims = 3\nDimSize = " << n[0] << " " << n[1] << " " << n[2]
         << "\nElementType = MET_FLOAT\nElementSpacing = " << spacing[0] << " " << spacing[1] << " " << spacing[2]
         << "\nOffset = 4 5 6\nTransformMatrix =";
    for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t c = 0; c < 3; ++c) {
            head << " " << r[a][c];  // MetaIO lists axis a's direction as the a-th triple
            file.step[a][c] = r[a][c] * spacing[a];
        }
    head << "\nElementByteOrderMSB = False\nElementDataFile = LOCAL\n";
    const Vec centre = file.at({6.5, 7.5, 5.5});
    const std::string path = s.file("rot.mha", head.str() + sphere_samples(n, file, centre, 8));
    const VolumeInfo info = read_volume_info(path);
    CHECK(info.rotation_dropped);
    CHECK(info.flipped == std::array<bool, 3>{false, true, false});
    check_samples_placed(info, file);
    check_sphere(path, centre, 8, 0.25);
}

// Every position fits a float in the loaded grid (read_volume checks that), but the file's
// affine puts some past FLT_MAX: to_world must refuse before touching the mesh, not write inf.
TEST_CASE("world: to_world refuses positions beyond the float range, leaving the mesh", "[world][nrrd]") {
    Scratch s;
    const Dims n{4, 5, 3};
    Affine file;
    file.origin = {3e38, 0, 0};
    file.step = {{{0, 1, 0}, {2e37, 0, 0}, {0, 0, 1}}};  // y's last sample: 3e38 + 8e37 in world x
    const Vec far = file.at({0, double(n[1] - 1), 0});
    REQUIRE(far[0] > double(FLT_MAX));
    const std::string path = s.file("far.nrrd", nrrd_file(n, file, sphere_samples(n, file, file.origin, 1)));
    const VolumeInfo info = read_volume_info(path);
    REQUIRE(info.rotation_dropped);
    Mesh corners;  // the loaded grid's corners, as extract would place them
    for (std::size_t c = 0; c < 8; ++c)
        for (std::size_t a = 0; a < 3; ++a)
            corners.positions.push_back(float(info.origin[a] + ((c >> a & 1) ? double(n[a] - 1) * info.spacing[a] : 0)));
    corners.normals.assign(corners.positions.size(), 0.5f);
    corners.indices = {0, 1, 2, 3, 4, 5};
    const Mesh before = corners;
    CHECK_THROWS_WITH(to_world(corners, info), Catch::Contains("beyond the range of float"));
    CHECK(vmtest::same_bits(corners.positions, before.positions));
    CHECK(vmtest::same_bits(corners.normals, before.normals));
    CHECK(corners.indices == before.indices);

    // Only the far corners overflow: the grid's first y slab still moves.
    Mesh near;
    for (std::size_t c = 0; c < 8; ++c)
        for (std::size_t a = 0; a < 3; ++a)
            near.positions.push_back(float(info.origin[a] + ((c >> a & 1) && a != 1 ? double(n[a] - 1) * info.spacing[a] : 0)));
    REQUIRE_NOTHROW(to_world(near, info));
    for (const float p : near.positions) CHECK(std::isfinite(p));

    // The same for a transform given directly, and for a mesh that is already not finite.
    VolumeInfo shifted;
    shifted.directions = {0, 1, 0, 1, 0, 0, 0, 0, 1};
    shifted.world_origin = {0, -3.3e38, 0};
    Mesh one;
    one.positions = {0, 0, 0, -2e37f, 0, 0};  // world y: -3.3e38 - 2e37
    const Mesh one_before = one;
    CHECK_THROWS_WITH(to_world(one, shifted), Catch::Contains("beyond the range of float"));
    CHECK(vmtest::same_bits(one.positions, one_before.positions));
    one.positions = {0, 0, 0, 1, INFINITY, 0};
    CHECK_THROWS_WITH(to_world(one, shifted), Catch::Contains("non-finite position"));
}

// A NaN or inf TransformMatrix component used to be skipped, so the mesh landed unrotated
// without a word (NIfTI's sform and quaternion: test_io_nifti.cpp).
TEST_CASE("world: a non-finite MetaImage direction is an error naming its field", "[world][metaimage][errors]") {
    Scratch s;
    const Dims n{4, 4, 4};
    Affine file;
    file.step = {{{2, 0, 0}, {0, 2, 0}, {0, 0, 2}}};
    const std::string samples = sphere_samples(n, file, {3, 3, 3}, 2);
    // The value named as it stands in the header (1-based), and the index axis it belongs to.
    const std::pair<const char*, const char*> cases[] = {
        {"nan 0 0 0 1 0 0 0 1", "TransformMatrix value 1 is nan: a non-finite direction component of index axis 0"},
        {"0 1 0 inf 0 0 0 0 1", "TransformMatrix value 4 is inf: a non-finite direction component of index axis 1"}};
    for (const auto& [matrix, message] : cases) {
        const std::string path =
            s.file("nan.mha", std::string("ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_FLOAT\n"
                                          "TransformMatrix = ") +
                                  matrix + "\nElementByteOrderMSB = False\nElementDataFile = LOCAL\n" + samples);
        INFO(matrix);
        CHECK_THROWS_WITH(read_volume_info(path), Catch::Contains(path) && Catch::Contains(message));
    }
}

// VTK's reader keeps the last SPACING; its sign was applied once per line, so a second
// negative SPACING undid the first's reversal and mirrored the volume.
TEST_CASE("world: a legacy VTK file's last SPACING holds, sign included", "[world][vtk]") {
    Scratch s;
    const Dims n{5, 4, 3};
    Affine file;
    file.origin = {1, 2, 3};
    file.step = {{{-2, 0, 0}, {0, 1.5, 0}, {0, 0, -1}}};
    std::string samples;  // big-endian floats: file sample f holds its flat index
    for (std::size_t i = 0; i < n[0] * n[1] * n[2]; ++i) {
        const float v = float(i);
        unsigned char b[4];
        std::memcpy(b, &v, 4);
        for (int k = 3; k >= 0; --k) samples += char(b[k]);
    }
    const std::string head = "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 5 4 3\n"
                             "SPACING -1 1 -1\nSPACING -2 1.5 -1\nORIGIN 1 2 3\nPOINT_DATA 60\nSCALARS v float 1\n"
                             "LOOKUP_TABLE default\n";
    const std::string path = s.file("twice.vtk", head + samples);
    VolumeInfo info;
    const Volume v = read_volume(path, info);
    CHECK(info.flipped == std::array<bool, 3>{true, false, true});
    check_samples_placed(info, file);
    // Each loaded sample holds the file sample placed there.
    const float* values = static_cast<const float*>(v.data);
    iotest::for_each_sample_of_file(info.dims, info.flipped, [&](std::size_t at, std::array<std::size_t, 3> f) {
        REQUIRE(values[at] == float(f[0] + n[0] * (f[1] + n[1] * f[2])));
    });
}
