// Helpers of the C API tests (see c_api.hpp); built where the tests link libvoxmesh_c.
#ifdef VOXMESH_TEST_C_API
#include "support/c_api.hpp"

#include <cstring>
#include <vector>

namespace capitest {

namespace {

template <class T>
bool same_bytes(const T* c, const std::vector<T>& cpp) {
    if (cpp.empty()) return c == nullptr;
    return c && std::memcmp(c, cpp.data(), cpp.size() * sizeof(T)) == 0;
}

}  // namespace

voxmesh_volume_view c_view(const voxmesh::VolumeView& v) {
    voxmesh_volume_view view{};
    view.data = v.data;
    view.type = static_cast<int>(v.type);
    for (int a = 0; a < 3; ++a) {
        view.dims[a] = v.dims[a];
        view.spacing[a] = v.spacing[a];
        view.origin[a] = v.origin[a];
    }
    return view;
}

void require_same(const voxmesh_mesh* c, const voxmesh::Mesh& cpp) {
    REQUIRE(voxmesh_mesh_vertex_count(c) == cpp.vertex_count());
    REQUIRE(voxmesh_mesh_triangle_count(c) == cpp.triangle_count());
    CHECK(same_bytes(voxmesh_mesh_positions(c), cpp.positions));
    CHECK(same_bytes(voxmesh_mesh_normals(c), cpp.normals));
    CHECK(same_bytes(voxmesh_mesh_indices(c), cpp.indices));
}

void require_same(const voxmesh_volume_view& c, const voxmesh::Volume& cpp) {
    REQUIRE(c.type == static_cast<int>(cpp.type));
    for (int a = 0; a < 3; ++a) {
        CHECK(c.dims[a] == cpp.dims[a]);
        CHECK(c.spacing[a] == cpp.spacing[a]);
        CHECK(c.origin[a] == cpp.origin[a]);
    }
    CHECK(std::memcmp(c.data, cpp.data, cpp.byte_size()) == 0);
}

MeshPtr extract_c(const voxmesh_volume_view& view, const voxmesh_options& options) {
    voxmesh_mesh* made = nullptr;
    const voxmesh_status status = voxmesh_extract(&view, &options, &made);
    INFO(voxmesh_last_error());
    REQUIRE(status == VOXMESH_OK);
    return MeshPtr(made, voxmesh_mesh_free);
}

}  // namespace capitest
#endif  // VOXMESH_TEST_C_API
