// The volume readers' common shape: each parses its header into what the file holds
// (VolumeInfo) and where the samples are (SampleLayout); read_volume.cpp loads them.
#pragma once

#include "samples.hpp"

#include <voxmesh/io.hpp>

#include <string>
#include <vector>

namespace voxmesh::io {

struct VolumeHeader {
    VolumeInfo info;
    SampleLayout layout;
};

VolumeHeader read_nrrd_header(const std::string& path);
VolumeHeader read_metaimage_header(const std::string& path);
VolumeHeader read_nifti_header(const std::string& path);

// N-D sizes as 3-D dims: N must be at least 3, and axes past the third must have size 1.
std::array<std::size_t, 3> volume_dims(const std::string& path, const std::vector<std::size_t>& sizes);

// Spacing must be finite and non-zero (negative is taken as its magnitude).
double checked_spacing(const std::string& path, const char* field, double value);
double checked_origin(const std::string& path, const char* field, double value);

}  // namespace voxmesh::io
