/* The C API from C itself (C99, -Wall -Wextra -pedantic -Werror): a sphere meshed on 1 and 2
 * threads must give identical buffers and a closed surface (every edge in two triangles,
 * Euler characteristic 2), bad arguments must fail with a status and a message naming the
 * problem, a mesh must write to a file, and a cube made from arrays must voxelize and mesh back
 * closed, a sculpt's edit must re-mesh only some blocks and weld to extract's mesh, and a
 * sculpt from a C function must take a stroke script. Exits 0 only when every check passes.
 *
 *   c_api_program <scratch-dir> <volume-file>   (a NRRD it must read; headsq.nrrd) */
#include <voxmesh/voxmesh.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond)                                                        \
    do {                                                                   \
        if (!(cond)) {                                                     \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                    \
        }                                                                  \
    } while (0)

static int contains(const char* text, const char* part) { return strstr(text, part) != NULL; }

/* A ball of radius *user around the centre of a 33^3 volume, positive inside. */
static double ball_field(double x, double y, double z, void* user) {
    return *(const double*)user - sqrt((x - 16.2) * (x - 16.2) + (y - 15.9) * (y - 15.9) + (z - 16.1) * (z - 16.1));
}

static int count_frame(const voxmesh_stroke_frame* frame, void* user) {
    size_t* frames = (size_t*)user;
    if (frame->frame == *frames) ++*frames; /* frames come in order */
    return 0;
}

static int compare_keys(const void* a, const void* b) {
    const unsigned long long x = *(const unsigned long long*)a, y = *(const unsigned long long*)b;
    return x < y ? -1 : x > y;
}

/* Every edge in exactly two triangles, and V - E + F. */
static int closed_with_euler(const voxmesh_mesh* mesh, long* euler) {
    const size_t t = voxmesh_mesh_triangle_count(mesh);
    const uint32_t* idx = voxmesh_mesh_indices(mesh);
    unsigned long long* keys = malloc(3 * t * sizeof *keys);
    size_t i, edges = 0;
    int closed = 1;
    if (!keys) return 0;
    for (i = 0; i < 3 * t; ++i) {
        const unsigned long long a = idx[i], b = idx[i % 3 == 2 ? i - 2 : i + 1];
        keys[i] = a < b ? a << 32 | b : b << 32 | a;
    }
    qsort(keys, 3 * t, sizeof *keys, compare_keys);
    for (i = 0; i < 3 * t;) {
        size_t run = 1;
        while (i + run < 3 * t && keys[i + run] == keys[i]) ++run;
        if (run != 2) closed = 0;
        ++edges;
        i += run;
    }
    free(keys);
    *euler = (long)voxmesh_mesh_vertex_count(mesh) - (long)edges + (long)t;
    return closed;
}

int main(int argc, char** argv) {
    enum { N = 40 };
    static float samples[N * N * N];
    voxmesh_volume_view view;
    voxmesh_options options = voxmesh_default_options();
    voxmesh_mesh *one = NULL, *two = NULL, *none = NULL;
    voxmesh_volume* file = NULL;
    char path[4096];
    long euler = 0;
    int x, y, z;
    if (argc != 3) {
        fprintf(stderr, "usage: c_api_program <scratch-dir> <volume-file>\n");
        return 2;
    }
    /* Found by a review: the version macros were only in voxmesh.hpp, not in the C header. */
    snprintf(path, sizeof path, "%d.%d.%d", VOXMESH_VERSION_MAJOR, VOXMESH_VERSION_MINOR, VOXMESH_VERSION_PATCH);
    CHECK(strcmp(voxmesh_version(), path) == 0);
    CHECK(strcmp(voxmesh_version(), VOXMESH_VERSION_STRING) == 0);
    CHECK(options.normals == 1 && options.threads == 0 && options.iso == 0 && options.backend == VOXMESH_BACKEND_AUTO);

    for (z = 0; z < N; ++z)
        for (y = 0; y < N; ++y)
            for (x = 0; x < N; ++x) {
                const double c = (N - 1) / 2.0;
                samples[x + N * (y + N * z)] =
                    (float)(14.0 - sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)));
            }
    memset(&view, 0, sizeof view);
    view.data = samples;
    view.type = VOXMESH_F32;
    view.dims[0] = view.dims[1] = view.dims[2] = N;
    view.spacing[0] = view.spacing[1] = view.spacing[2] = 1.0;

    options.backend = VOXMESH_BACKEND_CPU;
    options.threads = 1;
    CHECK(voxmesh_extract(&view, &options, &one) == VOXMESH_OK);
    options.threads = 2;
    CHECK(voxmesh_extract(&view, &options, &two) == VOXMESH_OK);
    if (!one || !two) return 1;
    {
        const size_t v = voxmesh_mesh_vertex_count(one), t = voxmesh_mesh_triangle_count(one);
        CHECK(v > 1000 && t > 2000);
        CHECK(v == voxmesh_mesh_vertex_count(two) && t == voxmesh_mesh_triangle_count(two));
        CHECK(memcmp(voxmesh_mesh_indices(one), voxmesh_mesh_indices(two), 3 * t * sizeof(uint32_t)) == 0);
        CHECK(memcmp(voxmesh_mesh_positions(one), voxmesh_mesh_positions(two), 3 * v * sizeof(float)) == 0);
        CHECK(memcmp(voxmesh_mesh_normals(one), voxmesh_mesh_normals(two), 3 * v * sizeof(float)) == 0);
        CHECK(closed_with_euler(one, &euler));
        CHECK(euler == 2);
    }

    /* Normals off: no normal array. */
    options.normals = 0;
    CHECK(voxmesh_extract(&view, &options, &none) == VOXMESH_OK);
    CHECK(none && voxmesh_mesh_normals(none) == NULL);
    voxmesh_mesh_free(none);
    none = NULL;

    /* Bad arguments: a status, no mesh, and a message that names the problem. */
    CHECK(voxmesh_extract(NULL, &options, &none) == VOXMESH_ERROR && none == NULL);
    CHECK(contains(voxmesh_last_error(), "volume is NULL"));
    view.dims[2] = 1;
    CHECK(voxmesh_extract(&view, &options, &none) == VOXMESH_ERROR && none == NULL);
    CHECK(contains(voxmesh_last_error(), "dimension"));
    view.dims[2] = N;
    view.type = 42;
    CHECK(voxmesh_extract(&view, &options, &none) == VOXMESH_ERROR);
    CHECK(contains(voxmesh_last_error(), "unknown scalar type 42"));
    view.type = VOXMESH_F32;
    options.backend = 9;
    CHECK(voxmesh_extract(&view, &options, &none) == VOXMESH_ERROR);
    CHECK(contains(voxmesh_last_error(), "unknown backend 9"));
    CHECK(voxmesh_extract(&view, NULL, NULL) == VOXMESH_ERROR);
    CHECK(contains(voxmesh_last_error(), "mesh pointer is NULL"));
    snprintf(path, sizeof path, "%s/no-such-volume.nrrd", argv[1]);
    CHECK(voxmesh_read_volume(path, &file) == VOXMESH_ERROR && file == NULL);
    CHECK(contains(voxmesh_last_error(), "no-such-volume.nrrd"));
    snprintf(path, sizeof path, "%s/mesh.xyz", argv[1]);
    CHECK(voxmesh_write_mesh(path, one) == VOXMESH_ERROR);
    CHECK(contains(voxmesh_last_error(), "xyz"));

    /* NULL is safe where nothing can be reported. */
    CHECK(voxmesh_mesh_vertex_count(NULL) == 0 && voxmesh_mesh_indices(NULL) == NULL);
    voxmesh_mesh_free(NULL);
    voxmesh_volume_free(NULL);

    /* A real file: read, mesh with the defaults, write. */
    CHECK(voxmesh_read_volume(argv[2], &file) == VOXMESH_OK);
    if (file) {
        const voxmesh_volume_view read = voxmesh_volume_get_view(file);
        voxmesh_mesh* head = NULL;
        voxmesh_options at = voxmesh_default_options();
        at.iso = 499.5;
        CHECK(read.data != NULL && read.dims[0] > 1 && read.dims[1] > 1 && read.dims[2] > 1);
        CHECK(voxmesh_extract(&read, &at, &head) == VOXMESH_OK);
        CHECK(voxmesh_mesh_triangle_count(head) == 57698); /* vtkFlyingEdges3D's count */
        snprintf(path, sizeof path, "%s/head.stl", argv[1]);
        CHECK(voxmesh_write_mesh(path, head) == VOXMESH_OK);
        {
            FILE* f = fopen(path, "rb");
            long size = -1;
            if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
            if (f) fclose(f);
            CHECK(size == 84 + 50L * 57698);
        }
        voxmesh_mesh_free(head);
        voxmesh_volume_free(file);
    }

    /* A model from arrays (a cube, wound outward), voxelized and meshed back: closed, Euler 2. */
    {
        static const float corners[8 * 3] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 4, 4, 0, 0, 0, 4, 4, 0, 4, 0, 4, 4, 4, 4, 4};
        static const uint32_t faces[12 * 3] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                               2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
        voxmesh_mesh *cube = NULL, *back = NULL;
        voxmesh_volume* grid = NULL;
        voxmesh_voxelize_options vox = voxmesh_default_voxelize_options();
        voxmesh_topology topology;
        vox.resolution = 32;
        CHECK(voxmesh_mesh_from_arrays(corners, 8, faces, 12, &cube) == VOXMESH_OK);
        CHECK(voxmesh_analyze_topology(cube, &topology) == VOXMESH_OK);
        CHECK(topology.boundary_edges == 0 && topology.nonmanifold_edges == 0 && topology.euler == 2);
        CHECK(voxmesh_voxelize(cube, &vox, &grid) == VOXMESH_OK);
        if (grid) {
            const voxmesh_volume_view distance = voxmesh_volume_get_view(grid);
            CHECK(distance.type == VOXMESH_F32);
            CHECK(voxmesh_extract(&distance, NULL, &back) == VOXMESH_OK);
            CHECK(voxmesh_analyze_topology(back, &topology) == VOXMESH_OK);
            CHECK(topology.boundary_edges == 0 && topology.nonmanifold_edges == 0 && topology.euler == 2);
        }
        voxmesh_mesh_free(back);
        voxmesh_volume_free(grid);
        voxmesh_mesh_free(cube);
    }

    /* Sculpting the sphere: a dab re-meshes some blocks, not all, the surface stays closed, and
     * the welded mesh is what an extract of the edited samples gives. */
    {
        voxmesh_sculpt* sculpt = NULL;
        voxmesh_sculpt_options so = voxmesh_default_sculpt_options();
        voxmesh_update_result result;
        voxmesh_mesh *sculpted = NULL, *fresh = NULL;
        const double center[3] = {N / 2.0, N / 2.0, N / 2.0 + 14.0};
        so.block_size = 8;
        CHECK(voxmesh_sculpt_new(&view, &so, &sculpt) == VOXMESH_OK);
        CHECK(voxmesh_sculpt_update(sculpt, &result) == VOXMESH_OK);
        CHECK(result.remeshed == voxmesh_sculpt_block_count(sculpt));
        CHECK(voxmesh_sculpt_apply(sculpt, VOXMESH_BRUSH_ADD, center, 4.0, 3.0, VOXMESH_UNITS_SAMPLES) == VOXMESH_OK);
        CHECK(voxmesh_sculpt_update(sculpt, &result) == VOXMESH_OK);
        CHECK(result.changed_count > 0 && result.remeshed < voxmesh_sculpt_block_count(sculpt));
        CHECK(voxmesh_sculpt_mesh(sculpt, &sculpted) == VOXMESH_OK);
        if (sculpted) {
            const voxmesh_volume_view edited = voxmesh_sculpt_get_view(sculpt);
            size_t t = voxmesh_mesh_triangle_count(sculpted);
            CHECK(voxmesh_extract(&edited, NULL, &fresh) == VOXMESH_OK);
            CHECK(t > voxmesh_mesh_triangle_count(one) && t == voxmesh_mesh_triangle_count(fresh));
            CHECK(fresh &&
                  memcmp(voxmesh_mesh_indices(sculpted), voxmesh_mesh_indices(fresh), 3 * t * sizeof(uint32_t)) == 0);
            CHECK(closed_with_euler(sculpted, &euler));
            CHECK(euler == 2);
        }
        CHECK(voxmesh_sculpt_apply(sculpt, 99, center, 4.0, 3.0, VOXMESH_UNITS_SAMPLES) == VOXMESH_ERROR);
        CHECK(contains(voxmesh_last_error(), "unknown brush 99"));
        voxmesh_mesh_free(fresh);
        voxmesh_mesh_free(sculpted);
        voxmesh_sculpt_free(sculpt);
    }

    /* A sculpt made from a C function, then a stroke script in memory: each frame is told to
     * the callback, and the surface stays closed. */
    {
        voxmesh_sculpt* sculpt = NULL;
        voxmesh_mesh* sculpted = NULL;
        const size_t dims[3] = {33, 33, 33};
        double radius = 11.0;
        size_t frames = 0;
        const char* script = "add 16 16 27 4 2\nsubtract 16 5 16 3 1.5\n";
        CHECK(voxmesh_sculpt_from_function(dims, VOXMESH_F32, ball_field, &radius, NULL, &sculpt) == VOXMESH_OK);
        CHECK(voxmesh_sculpt_run_strokes(sculpt, script, strlen(script), "s.txt", count_frame, &frames) == VOXMESH_OK);
        CHECK(frames == 2);
        CHECK(voxmesh_sculpt_mesh(sculpt, &sculpted) == VOXMESH_OK);
        CHECK(sculpted && closed_with_euler(sculpted, &euler) && euler == 2);
        CHECK(voxmesh_sculpt_run_strokes(sculpt, "add 1 2\n", 8, "s.txt", NULL, NULL) == VOXMESH_ERROR);
        CHECK(contains(voxmesh_last_error(), "s.txt:1:"));
        voxmesh_mesh_free(sculpted);
        voxmesh_sculpt_free(sculpt);
    }

    voxmesh_mesh_free(one);
    voxmesh_mesh_free(two);
    if (failures) fprintf(stderr, "%d check(s) failed\n", failures);
    else printf("C API: all checks passed\n");
    return failures ? 1 : 0;
}
