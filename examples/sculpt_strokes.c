/* The paper's sculpting loop from C: a sculpt made from a C function (a ball's signed distance),
 * a stroke script run on it with each dab's update reported by a callback, the mesh written.
 *
 *   sculpt_strokes [strokes.txt] [out.ply]
 *
 * Without a script it runs a built-in one (a ridge of dabs over the ball's top, then a smooth).
 * Exits 0 only when the sculpted surface is still closed with Euler characteristic 2; on any
 * failure prints voxmesh's message and exits 1. */
#include <voxmesh/voxmesh.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#define N 96

/* Positive inside a ball of radius *user around the volume's centre (called from several
 * threads: it only reads). */
static double ball(double x, double y, double z, void* user) {
    const double c = (N - 1) / 2.0;
    return *(const double*)user - sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c));
}

static int report(const voxmesh_stroke_frame* f, void* user) {
    static const char* const brushes[] = {"add", "subtract", "smooth", "set"};
    (void)user;
    printf("line %3zu %-8s at (%5.1f, %5.1f, %5.1f) r %4.1f: %3zu blocks re-meshed, %3zu changed, %6.2f ms\n",
           f->line, brushes[f->brush], f->center[0], f->center[1], f->center[2], f->radius, f->blocks_remeshed,
           f->blocks_changed, f->update_seconds * 1e3);
    return 0; /* nonzero would stop the script here */
}

static const char builtin[] =
    "# a ridge over the ball's top (z = 47.5 + 30), then smoothed\n"
    "add 35 47.5 77 5 2\n"
    "add 41 47.5 78 5 2\n"
    "add 47 47.5 78 5 2\n"
    "add 53 47.5 78 5 2\n"
    "add 59 47.5 77 5 2\n"
    "subtract 47.5 47.5 17 6 3   # a dent underneath\n"
    "smooth 47 47.5 79 8 0.7\n";

int main(int argc, char** argv) {
    const size_t dims[3] = {N, N, N};
    double radius = 30.0;
    voxmesh_sculpt* sculpt = NULL;
    voxmesh_mesh* mesh = NULL;
    voxmesh_topology topology;
    voxmesh_sculpt_options options = voxmesh_default_sculpt_options();
    voxmesh_status ran;
    int status = 1;
    options.block_size = 16;
    if (voxmesh_sculpt_from_function(dims, VOXMESH_F32, ball, &radius, &options, &sculpt) != VOXMESH_OK) goto done;
    if (voxmesh_sculpt_update(sculpt, NULL) != VOXMESH_OK) goto done; /* every block, once */
    ran = argc > 1 ? voxmesh_sculpt_run_stroke_script(sculpt, argv[1], report, NULL)
                   : voxmesh_sculpt_run_strokes(sculpt, builtin, strlen(builtin), "builtin", report, NULL);
    if (ran != VOXMESH_OK) goto done;
    if (voxmesh_sculpt_mesh(sculpt, &mesh) != VOXMESH_OK) goto done;
    if (argc > 2 && voxmesh_write_mesh(argv[2], mesh) != VOXMESH_OK) goto done;
    if (voxmesh_analyze_topology(mesh, &topology) != VOXMESH_OK) goto done;
    printf("%zu blocks; %zu vertices, %zu triangles; boundary edges %zu, non-manifold %zu, Euler %lld\n",
           voxmesh_sculpt_block_count(sculpt), voxmesh_mesh_vertex_count(mesh), voxmesh_mesh_triangle_count(mesh),
           topology.boundary_edges, topology.nonmanifold_edges, topology.euler);
    if (topology.boundary_edges != 0 || topology.nonmanifold_edges != 0 || topology.euler != 2) {
        fprintf(stderr, "sculpt_strokes: the surface is no longer a closed sphere-like surface\n");
        status = 2;
    } else {
        status = 0;
    }
done:
    if (status == 1) fprintf(stderr, "sculpt_strokes: %s\n", voxmesh_last_error());
    voxmesh_mesh_free(mesh);
    voxmesh_sculpt_free(sculpt);
    return status;
}
