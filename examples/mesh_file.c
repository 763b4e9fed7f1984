/* The C API from a C program: read a volume file, mesh it, write the mesh.
 *
 *   mesh_file <volume> <iso> <out.stl|.ply|.obj>
 *
 * Prints the counts and exits 0; on any failure prints voxmesh's message and exits 1. */
#include <voxmesh/voxmesh.h>

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char** argv) {
    voxmesh_volume* volume = NULL;
    voxmesh_mesh* mesh = NULL;
    voxmesh_options options = voxmesh_default_options(); /* every field its default first */
    voxmesh_volume_view view;
    int status = 1;
    if (argc != 4) {
        fprintf(stderr, "usage: %s <volume> <iso> <out.stl|.ply|.obj>\n", argv[0]);
        return 2;
    }
    options.iso = atof(argv[2]);
    if (voxmesh_read_volume(argv[1], &volume) != VOXMESH_OK) goto done;
    view = voxmesh_volume_get_view(volume);
    if (voxmesh_extract(&view, &options, &mesh) != VOXMESH_OK) goto done;
    if (voxmesh_write_mesh(argv[3], mesh) != VOXMESH_OK) goto done;
    printf("%s: %zux%zux%zu samples, iso %g: %zu vertices, %zu triangles -> %s (voxmesh %s)\n", argv[1],
           view.dims[0], view.dims[1], view.dims[2], options.iso, voxmesh_mesh_vertex_count(mesh),
           voxmesh_mesh_triangle_count(mesh), argv[3], voxmesh_version());
    status = 0;
done:
    if (status) fprintf(stderr, "mesh_file: %s\n", voxmesh_last_error());
    voxmesh_mesh_free(mesh);
    voxmesh_volume_free(volume);
    return status;
}
