// Reading and writing volumes and meshes. Every reader checks its header against the file
// before allocating and throws voxmesh::Error naming the file and the problem.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cstddef>
#include <string>

namespace voxmesh {

// Headerless samples: the caller says what they are.
struct RawLayout {
    std::array<std::size_t, 3> dims{0, 0, 0};
    ScalarType type = ScalarType::U8;
    bool big_endian = false;
    std::size_t offset = 0;  // bytes to skip before the first sample
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
};
Volume read_raw(const std::string& path, const RawLayout& layout);

// What a volume file holds, read from its header only.
struct VolumeInfo {
    std::string format;  // "nrrd", "metaimage", "nifti", "raw"
    ScalarType type = ScalarType::U8;
    std::array<std::size_t, 3> dims{0, 0, 0};
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
    std::string encoding;     // "raw", "gzip"
    std::size_t file_bytes = 0;
};

// NRRD (.nrrd, .nhdr), MetaImage (.mhd, .mha), NIfTI-1 (.nii, .nii.gz), chosen by extension.
Volume read_volume(const std::string& path);
VolumeInfo read_volume_info(const std::string& path);

// NRRD with raw encoding, through a temporary file renamed into place.
void write_nrrd(const std::string& path, const VolumeView& volume);

// STL, binary or ASCII (detected by size, not by the "solid" prefix), welded by exact
// position: positions and indices filled, normals empty.
Mesh read_stl(const std::string& path);

}  // namespace voxmesh
