// Where a file cannot be memory-mapped (a FUSE or network mount without mmap, the map-count
// limit), every reader that maps falls back to reading the file into memory and returns
// the same data.
#include <catch2/catch.hpp>
#include <voxmesh/io.hpp>

#include "io/input_file.hpp"
#include "support/io_scratch.hpp"

#include <cstring>
#include <string>

using namespace voxmesh;

namespace {

std::string test_data(const std::string& name) { return std::string(VOXMESH_TEST_DATA) + "/" + name; }

// Turns the mmap refusal on for one scope.
struct NoMmap {
    NoMmap() { io::refuse_mmap_for_testing(true); }
    ~NoMmap() { io::refuse_mmap_for_testing(false); }
    NoMmap(const NoMmap&) = delete;
    NoMmap& operator=(const NoMmap&) = delete;
};

bool same_samples(const Volume& a, const Volume& b) {
    return a.type == b.type && a.dims == b.dims && a.spacing == b.spacing && a.origin == b.origin &&
           std::memcmp(a.data, b.data, a.sample_count() * scalar_size(a.type)) == 0;
}

}  // namespace

TEST_CASE("volume readers read the file when it cannot be mapped", "[io][mmap]") {
    // headsq.nrrd: raw little-endian i16 after the header (the mapped path);
    // the MRI: gzip NIfTI (its header is inflated from a mapping).
    for (const char* name : {"headsq.nrrd", "mri_someones_anatomy.nii.gz"}) {
        INFO(name);
        const Volume mapped = read_volume(test_data(name));
        Volume read;
        {
            const NoMmap refuse;
            read = read_volume(test_data(name));
        }
        CHECK(same_samples(mapped, read));
        // Heap samples are not the mapping's: writing them must be allowed and private.
        std::memset(read.data, 0, scalar_size(read.type));
    }
}

TEST_CASE("mesh readers read the file when it cannot be mapped", "[io][mmap]") {
    iotest::Scratch s;
    const std::string obj = s.file("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string ply = s.file("t.ply",
                                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                   "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                   "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    for (const std::string& path : {test_data("torus.stl"), obj, ply}) {
        INFO(path);
        const Mesh mapped = read_mesh(path);
        Mesh read;
        {
            const NoMmap refuse;
            read = read_mesh(path);
        }
        CHECK(read.triangle_count() > 0);
        CHECK(read.positions == mapped.positions);
        CHECK(read.indices == mapped.indices);
    }
}

TEST_CASE("an empty file is still an error without mmap", "[io][mmap]") {
    iotest::Scratch s;
    const std::string empty = s.file("empty.stl", "");
    const NoMmap refuse;
    CHECK_THROWS_WITH(read_mesh(empty), Catch::Contains("empty.stl") && Catch::Contains("empty"));
}
