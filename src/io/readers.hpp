// The volume readers' common shape: each parses its header into what the file holds
// (VolumeInfo) and where the samples are (SampleLayout); read_volume.cpp loads them.
#pragma once

#include "input_file.hpp"
#include "samples.hpp"

#include <voxmesh/io.hpp>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace voxmesh::io {

struct VolumeHeader {
    VolumeInfo info;
    SampleLayout layout;
};

// Each reads the header at the start of `file` (which names it in errors).
VolumeHeader read_nrrd_header(const InputFile& file);
VolumeHeader read_metaimage_header(const InputFile& file);
VolumeHeader read_nifti_header(const InputFile& file);
VolumeHeader read_vtk_header(const InputFile& file);
VolumeHeader read_npy_header(const InputFile& file);

// N-D sizes as 3-D dims: N must be at least 3, and axes past the third must have size 1.
std::array<std::size_t, 3> volume_dims(const std::string& path, const std::vector<std::size_t>& sizes);
// The three axes of N-D `sizes` (fastest first) that hold a volume, for formats whose extra
// axes may lie anywhere (NumPy (z, y, x, 1)): axes beyond three must have size 1 and are
// dropped, those marked in `drop_first` (known not spatial) first, then the slowest.
std::array<std::size_t, 3> volume_axes(const std::string& path, const std::vector<std::size_t>& sizes,
                                       const std::vector<bool>& drop_first = {});

// Spacing must be finite and non-zero; the magnitude is returned (a caller whose format
// gives a negative spacing a direction passes that on with reverse_direction).
double checked_spacing(const std::string& path, const char* field, double value);
double checked_origin(const std::string& path, const char* field, double value);

// What a Volume keeps of a direction matrix: which index axes run in the negative
// direction of their own world axis, whether anything else (a rotation) is left out of the
// samples' placement, and the file's unit directions (column a: index axis a, before flips;
// identity-with-flips unless rotation_dropped) for VolumeInfo's world transform.
struct AxisDirections {
    std::array<bool, 3> flipped{false, false, false};
    bool rotation_dropped = false;
    std::array<double, 9> directions{1, 0, 0, 0, 1, 0, 0, 0, 1};
};
// `axes[a]` is index axis a's direction vector in world components (any length; components
// past the third count as off-axis). A zero vector says nothing and is left alone.
AxisDirections axis_directions(const std::array<std::vector<double>, 3>& axes);
// Fails where a direction component is NaN or infinite (axis_directions would otherwise skip
// that axis, silently keeping the samples unrotated), naming it as the header does:
// name(a, c) for component c of index axis a's direction (NIfTI's srow_y[2], MetaImage's
// TransformMatrix value).
void check_directions(const std::string& path, const std::array<std::vector<double>, 3>& axes,
                      const std::function<std::string(std::size_t axis, std::size_t component)>& name);
// A direction vector's length (an axis's spacing where the header gives vectors).
double vector_length(const std::vector<double>& v);
// A negative spacing along index axis a: its direction reversed, or, where the header gives
// none, the negative of world axis a.
void reverse_direction(std::array<std::vector<double>, 3>& axes, std::size_t a);

// Records `d` in the header and moves the origin of each flipped axis to the grid's minimum
// corner; load_samples then reverses those axes, so every sample keeps its world position.
// Also sets the world transform (directions, world_origin) for the flipped samples.
// Call once spacing, origin and dims are final.
void apply_directions(VolumeHeader& h, const AxisDirections& d);

}  // namespace voxmesh::io
