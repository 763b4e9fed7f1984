// to_world: a mesh extracted from a loaded Volume, moved into its file's world frame (see
// Geometry in include/voxmesh/io.hpp).
#include <voxmesh/io.hpp>

#include "header_text.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <utility>

namespace voxmesh {

bool has_world_transform(const VolumeInfo& info) {
    return info.directions != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1} || info.world_origin != info.origin;
}

void to_world(Mesh& mesh, const VolumeInfo& info) {
    if (mesh.positions.size() % 3 || mesh.indices.size() % 3)
        throw Error("to_world: positions and indices must be whole triples");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
        throw Error("to_world: normals are not one per vertex");
    // Identity: leave the floats as they are (p - origin + origin might round).
    if (!has_world_transform(info)) return;
    const std::array<double, 9>& m = info.directions;

    // Cofactors: the inverse-transpose is cof / det; its scale goes with renormalising, but
    // not its sign, which keeps outward normals outward under a mirroring.
    const std::array<double, 9> cof{m[4] * m[8] - m[5] * m[7], m[5] * m[6] - m[3] * m[8], m[3] * m[7] - m[4] * m[6],
                                    m[2] * m[7] - m[1] * m[8], m[0] * m[8] - m[2] * m[6], m[1] * m[6] - m[0] * m[7],
                                    m[1] * m[5] - m[2] * m[4], m[2] * m[3] - m[0] * m[5], m[0] * m[4] - m[1] * m[3]};
    const double det = m[0] * cof[0] + m[1] * cof[1] + m[2] * cof[2];
    bool finite = std::isfinite(det);
    for (std::size_t c = 0; c < 3; ++c) finite = finite && std::isfinite(info.origin[c]) && std::isfinite(info.world_origin[c]);
    if (!finite || det == 0) throw Error("to_world: the volume's direction matrix is singular or not finite");
    const double sign = det < 0 ? -1 : 1;

    // Positions are floats: a far world_origin (or origin) would turn them into inf, so check
    // before changing anything. The map is affine, so each world component is largest and
    // smallest at corners of the positions' bounding box (computed in double, as below).
    std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (std::size_t v = 0; v < mesh.positions.size(); v += 3)
        for (std::size_t c = 0; c < 3; ++c) {
            const double q = double(mesh.positions[v + c]) - info.origin[c];
            if (!std::isfinite(q)) throw Error("to_world: the mesh has a non-finite position");
            lo[c] = v == 0 ? q : std::min(lo[c], q);
            hi[c] = v == 0 ? q : std::max(hi[c], q);
        }
    if (!mesh.positions.empty())
        for (std::size_t corner = 0; corner < 8; ++corner) {
            double q[3];
            for (std::size_t a = 0; a < 3; ++a) q[a] = (corner >> a & 1) ? hi[a] : lo[a];
            for (std::size_t c = 0; c < 3; ++c) {
                const double w = info.world_origin[c] + m[3 * c] * q[0] + m[3 * c + 1] * q[1] + m[3 * c + 2] * q[2];
                if (!(std::fabs(w) <= FLT_MAX))
                    throw Error("to_world: the volume's world transform puts mesh coordinates at " +
                                io::shortest_text(w) + ", beyond the range of float coordinates");
            }
        }

    for (std::size_t v = 0; v < mesh.positions.size(); v += 3) {
        const double q[3] = {mesh.positions[v] - info.origin[0], mesh.positions[v + 1] - info.origin[1],
                             mesh.positions[v + 2] - info.origin[2]};
        for (std::size_t c = 0; c < 3; ++c)
            mesh.positions[v + c] =
                static_cast<float>(info.world_origin[c] + m[3 * c] * q[0] + m[3 * c + 1] * q[1] + m[3 * c + 2] * q[2]);
    }
    for (std::size_t v = 0; v < mesh.normals.size(); v += 3) {
        const double n[3] = {mesh.normals[v], mesh.normals[v + 1], mesh.normals[v + 2]};
        double w[3], length2 = 0;
        for (std::size_t c = 0; c < 3; ++c) {
            w[c] = sign * (cof[3 * c] * n[0] + cof[3 * c + 1] * n[1] + cof[3 * c + 2] * n[2]);
            length2 += w[c] * w[c];
        }
        const double scale = length2 > 0 ? 1 / std::sqrt(length2) : 0;  // a zero normal stays zero
        for (std::size_t c = 0; c < 3; ++c) mesh.normals[v + c] = static_cast<float>(w[c] * scale);
    }
    if (det < 0)  // a mirroring turns counter-clockwise into clockwise seen from outside
        for (std::size_t t = 0; t < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
}

}  // namespace voxmesh
