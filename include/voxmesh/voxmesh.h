/* voxmesh's C API: the C++ library's extract, volume and mesh files, voxelize and the topology
 * check behind a C ABI, for C programs and for other languages' foreign-function interfaces
 * (Python's ctypes, Rust, Julia, C#). Link libvoxmesh_c (CMake: voxmesh::voxmesh_c).
 *
 * Every call that can fail returns a voxmesh_status; on failure voxmesh_last_error() gives the
 * message the C++ library would have thrown (naming the problem), for the calling thread.
 * Nothing throws or aborts across this boundary. Objects made here are freed here
 * (voxmesh_mesh_free, voxmesh_volume_free); freeing NULL does nothing.
 *
 * The structs are plain data. Fill voxmesh_options from voxmesh_default_options() so that
 * fields added in later versions get their defaults (0.x versions may add fields: rebuild
 * against the header you link). */
#ifndef VOXMESH_H
#define VOXMESH_H

#include <stddef.h>
#include <stdint.h>

#include "version.h" /* VOXMESH_VERSION_MAJOR, _MINOR, _PATCH, _STRING: what voxmesh_version() says */

#ifdef __cplusplus
extern "C" {
#endif

typedef enum voxmesh_status {
    VOXMESH_OK = 0,
    VOXMESH_ERROR = 1,         /* bad input or arguments: the message names the problem */
    VOXMESH_OUT_OF_MEMORY = 2, /* memory ran out during the call; may pass with more memory */
    VOXMESH_INTERNAL = 3       /* anything else (a bug: please report the message) */
} voxmesh_status;

typedef enum voxmesh_scalar_type {
    VOXMESH_U8 = 0,
    VOXMESH_I8 = 1,
    VOXMESH_U16 = 2,
    VOXMESH_I16 = 3,
    VOXMESH_U32 = 4,
    VOXMESH_I32 = 5,
    VOXMESH_F32 = 6,
    VOXMESH_F64 = 7
} voxmesh_scalar_type;

typedef enum voxmesh_backend {
    VOXMESH_BACKEND_AUTO = 0,
    VOXMESH_BACKEND_CPU = 1,
    VOXMESH_BACKEND_OPENCL = 2,
    VOXMESH_BACKEND_HYBRID = 3
} voxmesh_backend;

/* A non-owning view of x-fastest samples: index = x + nx * (y + ny * z), `data` aligned to the
 * sample size. Positions are origin + index * spacing. */
typedef struct voxmesh_volume_view {
    const void* data;
    int type; /* a voxmesh_scalar_type */
    size_t dims[3];
    double spacing[3];
    double origin[3];
} voxmesh_volume_view;

typedef enum voxmesh_device_type {
    VOXMESH_DEVICE_ANY = 0,
    VOXMESH_DEVICE_CPU = 1,
    VOXMESH_DEVICE_GPU = 2,
    VOXMESH_DEVICE_ACCELERATOR = 3
} voxmesh_device_type;

/* The C++ voxmesh::Options without the log (warnings are kept with the mesh:
 * voxmesh_mesh_warnings). */
typedef struct voxmesh_options {
    double iso;           /* a sample is inside when value >= iso */
    int backend;          /* a voxmesh_backend */
    unsigned threads;     /* 0: the CPUs this process may use */
    int normals;          /* nonzero: per-vertex normals */
    int inside_below;     /* nonzero: inside where value < iso (signed distance fields) */
    const int* devices;   /* OpenCL devices by index (voxmesh_get_device); NULL: every device */
    size_t device_count;  /*   of device_type */
    int device_type;      /* a voxmesh_device_type */
    size_t chunk_planes;  /* OpenCL and Hybrid: z-planes per chunk; 0: automatic */
    size_t memory_budget; /* OpenCL and Hybrid: bytes per device for one chunk; 0: the device's limits */
} voxmesh_options;

/* iso 0, backend auto, threads 0, normals on, inside_below off, every device of any type,
 * automatic chunks. */
voxmesh_options voxmesh_default_options(void);

/* The OpenCL devices (voxmesh::list_devices; none without OpenCL or a platform). */
typedef struct voxmesh_device {
    int index;             /* what voxmesh_options.devices names it by */
    int type;              /* a voxmesh_device_type */
    unsigned compute_units;
    uint64_t global_memory, max_allocation; /* bytes */
    int fp64;              /* nonzero: double precision, so vertices are bit-identical to the CPU's */
    int host_memory;       /* nonzero: shares the host's memory (zero-copy) */
    char platform[128], name[128], version[128]; /* truncated to fit, always terminated */
} voxmesh_device;
size_t voxmesh_device_count(void);
/* Frees the scratch memory the CPU engine and the OpenCL devices keep from one extract to the
 * next (voxmesh::release_scratch_memory), for a program done meshing large volumes; compiled
 * OpenCL programs stay, and a device another thread is meshing on keeps its buffers. */
void voxmesh_release_scratch_memory(void);
/* Device `index` (0 .. voxmesh_device_count() - 1). */
voxmesh_status voxmesh_get_device(size_t index, voxmesh_device* device);

/* Opaque: a volume (read from a file, or voxelized), and a mesh. */
typedef struct voxmesh_volume voxmesh_volume;
typedef struct voxmesh_mesh voxmesh_mesh;

/* The canonical mesh of `volume` at options->iso (options NULL: the defaults). On success
 * *mesh is a new mesh; on failure *mesh is NULL. */
voxmesh_status voxmesh_extract(const voxmesh_volume_view* volume, const voxmesh_options* options,
                               voxmesh_mesh** mesh);

/* As voxmesh_extract, into an existing mesh (one this API made), reusing the memory its arrays
 * already have: meshing again and again (a sculpting loop, an animation) writes pages already
 * mapped instead of fresh ones. The mesh's previous arrays, stats and warnings are replaced
 * (pointers taken from it before may no longer be valid); on failure it is left empty. */
voxmesh_status voxmesh_extract_into(const voxmesh_volume_view* volume, const voxmesh_options* options,
                                    voxmesh_mesh* mesh);

size_t voxmesh_mesh_vertex_count(const voxmesh_mesh* mesh);
size_t voxmesh_mesh_triangle_count(const voxmesh_mesh* mesh);
/* xyz per vertex; NULL for a mesh without vertices. Valid until voxmesh_mesh_free. */
const float* voxmesh_mesh_positions(const voxmesh_mesh* mesh);
/* xyz per vertex, unit, outward; NULL when normals were off or there are no vertices. */
const float* voxmesh_mesh_normals(const voxmesh_mesh* mesh);
/* three per triangle, counter-clockwise seen from outside; NULL without triangles. */
const uint32_t* voxmesh_mesh_indices(const voxmesh_mesh* mesh);
void voxmesh_mesh_free(voxmesh_mesh* mesh);

/* What the voxmesh_extract that made a mesh did (voxmesh::Stats); all zero, backend AUTO, for
 * a mesh it did not make. */
typedef struct voxmesh_stats {
    int backend;       /* the voxmesh_backend that ran: CPU, OPENCL or HYBRID */
    unsigned threads;  /* CPU slabs (options.threads resolved); 0 for OpenCL alone */
    unsigned workers;  /* CPU threads that ran them at once */
    double classify_s, scan_s, generate_s, total_s; /* seconds per pass, and in all */
} voxmesh_stats;
voxmesh_stats voxmesh_mesh_stats(const voxmesh_mesh* mesh);
/* Per device of that extract (voxmesh::DeviceStats): "cpu" or an OpenCL device, its chunks and
 * samples, and seconds; voxmesh_mesh_device_stats_count is 0 for a mesh no extract made. */
typedef struct voxmesh_device_stats {
    char name[128];              /* "cpu" or the OpenCL device's name (truncated, terminated) */
    size_t chunks, voxels;       /* chunks meshed, samples in them */
    double kernel_s, transfer_s, wall_s, setup_s; /* device time, copies, wall, program builds */
    size_t programs_built;       /* OpenCL programs compiled in this call (0 once cached) */
    size_t chunks_handed_over;   /* Hybrid: this device's chunks the CPU meshed instead */
} voxmesh_device_stats;
size_t voxmesh_mesh_device_stats_count(const voxmesh_mesh* mesh);
voxmesh_status voxmesh_mesh_get_device_stats(const voxmesh_mesh* mesh, size_t index, voxmesh_device_stats* stats);
/* That extract's warnings (a fallback to the CPU engine, a spacing too fine for float vertices,
 * ...), one a line; "" when there were none. Valid until voxmesh_mesh_free. */
const char* voxmesh_mesh_warnings(const voxmesh_mesh* mesh);

/* .stl, .ply, .obj or .glb (binary glTF 2.0) by extension, through a temporary renamed into place. */
voxmesh_status voxmesh_write_mesh(const char* path, const voxmesh_mesh* mesh);
/* STL (binary or ASCII), PLY or OBJ by extension (as voxmesh::read_mesh). */
voxmesh_status voxmesh_read_mesh(const char* path, voxmesh_mesh** mesh);
/* A mesh holding copies of `vertex_count` xyz positions and `triangle_count` index triples
 * (normals none). Not checked here: the calls that use a mesh check it (indices in range). */
voxmesh_status voxmesh_mesh_from_arrays(const float* positions, size_t vertex_count, const uint32_t* indices,
                                        size_t triangle_count, voxmesh_mesh** mesh);

/* Bytes made in memory (voxmesh_write_mesh_to_memory, voxmesh_write_nrrd_to_memory). */
typedef struct voxmesh_bytes voxmesh_bytes;
const unsigned char* voxmesh_bytes_data(const voxmesh_bytes* bytes); /* NULL when empty */
size_t voxmesh_bytes_size(const voxmesh_bytes* bytes);
void voxmesh_bytes_free(voxmesh_bytes* bytes);

/* The bytes voxmesh_write_mesh would write; `name` ("part.stl") picks the format by extension
 * and names the output in errors. */
voxmesh_status voxmesh_write_mesh_to_memory(const voxmesh_mesh* mesh, const char* name, voxmesh_bytes** bytes);
/* voxmesh_read_mesh over `size` bytes at `data`; `name` stands for the file's path. */
voxmesh_status voxmesh_read_mesh_from_memory(const void* data, size_t size, const char* name, voxmesh_mesh** mesh);

/* The `count` connected pieces with the most triangles, in their order (see
 * voxmesh::keep_largest_components): a CT's surface without the specks around it. */
voxmesh_status voxmesh_keep_largest_components(const voxmesh_mesh* mesh, size_t count, voxmesh_mesh** kept);

/* The samples summed up in one pass (voxmesh::value_range): the smallest and largest finite
 * sample (0 when none is), the NaN or infinite ones with the first's (x, y, z), and how many
 * finite samples equal *equal_to exactly (equal_to NULL: not counted, 0). */
typedef struct voxmesh_value_range {
    double min, max;
    uint64_t nonfinite;
    size_t first_nonfinite[3];
    uint64_t equal;
} voxmesh_value_range;
voxmesh_status voxmesh_compute_value_range(const voxmesh_volume_view* volume, const double* equal_to, unsigned threads,
                                           voxmesh_value_range* range);

/* The crossed edge under each vertex of voxmesh_extract(volume) at `iso` (voxmesh::vertex_edges):
 * vertex i lies on edges[i] = 3 * (x + nx * (y + ny * z)) + axis (0 x, 1 y, 2 z), (x, y, z) the
 * edge's lower end. *count gets how many there are (the mesh's vertex count). edges NULL asks for
 * the count alone; otherwise capacity must be at least the count (else an error naming both,
 * nothing written to edges, *count still set). */
voxmesh_status voxmesh_vertex_edges(const voxmesh_volume_view* volume, double iso, unsigned threads, uint64_t* edges,
                                    size_t capacity, size_t* count);
/* The cell each triangle of voxmesh_extract(volume) at `iso` lies in (voxmesh::triangle_cells):
 * triangle i lies in cells[i] = x + (nx - 1) * (y + (ny - 1) * z), (x, y, z) the cell's lowest
 * corner. *count gets the mesh's triangle count; cells NULL, capacity and errors as above. */
voxmesh_status voxmesh_triangle_cells(const voxmesh_volume_view* volume, double iso, unsigned threads, uint64_t* cells,
                                      size_t capacity, size_t* count);
/* For each of `count` edges (that numbering), the largest range, maximum minus minimum sample, of
 * the cells around it that the volume holds and cell_mask marks nonzero (NULL: every cell;
 * otherwise (nx-1)(ny-1)(nz-1) bytes, x fastest, a cell by its lowest corner), into ranges[0 ..
 * count-1]; see voxmesh::edge_cell_ranges (offset: scikit-image's level). */
voxmesh_status voxmesh_edge_cell_ranges(const voxmesh_volume_view* volume, const uint64_t* edges, size_t count,
                                        double offset, const uint8_t* cell_mask, unsigned threads, float* ranges);

/* voxmesh::MeshTopology: closed when both edge counts are 0. */
typedef struct voxmesh_topology {
    size_t boundary_edges;    /* edges in one triangle */
    size_t nonmanifold_edges; /* edges in three or more */
    long long euler;          /* V - E + F over the vertices triangles use */
    size_t components;        /* connected pieces (triangles sharing a vertex are in one) */
} voxmesh_topology;
voxmesh_status voxmesh_analyze_topology(const voxmesh_mesh* mesh, voxmesh_topology* topology);

/* A closed triangle mesh to a volume (voxmesh::voxelize; see voxmesh/voxelize.hpp). */
typedef enum voxmesh_voxel_field {
    VOXMESH_FIELD_OCCUPANCY = 0, /* u8: 255 inside, 0 outside; mesh it back at iso 127.5 */
    VOXMESH_FIELD_DISTANCE = 1   /* f32 signed distance, positive inside; mesh it back at iso 0 */
} voxmesh_voxel_field;
typedef enum voxmesh_fill_rule {
    VOXMESH_FILL_EVENODD = 0, /* inside after an odd number of crossings (any winding) */
    VOXMESH_FILL_NONZERO = 1  /* the union of closed shells (overlapping bodies); needs consistent winding */
} voxmesh_fill_rule;
typedef struct voxmesh_voxelize_options {
    size_t resolution; /* voxels along the longest side of the bounding box (2..4096) */
    size_t padding;    /* samples added outside the box on every side */
    int field;         /* a voxmesh_voxel_field */
    double band;       /* distance: exact within this many voxels (2..1000) */
    unsigned threads;  /* 0: the CPUs this process may use */
    int fill;          /* a voxmesh_fill_rule */
} voxmesh_voxelize_options;
/* resolution 128, padding 2, distance, band 3, threads 0, even-odd. */
voxmesh_voxelize_options voxmesh_default_voxelize_options(void);
voxmesh_status voxmesh_voxelize(const voxmesh_mesh* mesh, const voxmesh_voxelize_options* options,
                                voxmesh_volume** volume);

/* NRRD, MetaImage, NIfTI-1, legacy VTK or NumPy .npy, by extension (as voxmesh::read_volume). */
voxmesh_status voxmesh_read_volume(const char* path, voxmesh_volume** volume);
/* The same over `size` bytes at `data` (copied); `name` ("scan.nii.gz") stands for the path. */
voxmesh_status voxmesh_read_volume_from_memory(const void* data, size_t size, const char* name,
                                               voxmesh_volume** volume);

/* Headerless samples, described by the caller (voxmesh::RawLayout): the file holds exactly
 * offset + nx * ny * nz * sample size bytes. */
typedef struct voxmesh_raw_layout {
    size_t dims[3];
    int type;          /* a voxmesh_scalar_type */
    int big_endian;    /* nonzero: samples stored big-endian */
    size_t offset;     /* bytes before the first sample */
    double spacing[3];
    double origin[3];
} voxmesh_raw_layout;
/* dims 0, u8, little-endian, offset 0, spacing 1, origin 0. */
voxmesh_raw_layout voxmesh_default_raw_layout(void);
voxmesh_status voxmesh_read_raw(const char* path, const voxmesh_raw_layout* layout, voxmesh_volume** volume);

/* What the file said beyond the samples (voxmesh::VolumeInfo), for a volume read from a file
 * or bytes; all zero (value_scale 1) for a voxelized one. */
typedef struct voxmesh_volume_info {
    char format[16];      /* "nrrd", "metaimage", "nifti", "vtk", "npy", "raw"; "" when not read */
    char encoding[16];    /* "raw", "gzip" or "ascii" */
    int big_endian;       /* the stored samples' byte order */
    int flipped[3];       /* axes stored in the negative direction, reversed on load */
    int rotation_dropped; /* a direction matrix that is not diagonal was dropped */
    double value_scale, value_offset; /* NIfTI scl_slope / scl_inter (not applied): 1 and 0 elsewhere */
    /* The file's world transform (voxmesh::VolumeInfo): sample (i,j,k) lies at world_origin +
     * D * ((i,j,k) * spacing), D[c][a] = directions[3 * c + a]; the identity and the volume's
     * origin unless rotation_dropped. */
    double directions[9];
    double world_origin[3];
} voxmesh_volume_info;
voxmesh_volume_info voxmesh_volume_get_info(const voxmesh_volume* volume);
/* A mesh extracted from `volume` moved into its file's world frame (voxmesh::to_world):
 * positions by the affine, normals by its inverse-transpose, the winding reversed under a
 * mirroring; nothing changes for a volume without a rotation (or one not read from a file).
 * VOXMESH_ERROR, the mesh unchanged, where the transform would put a position beyond the float
 * range or a position is not finite. */
voxmesh_status voxmesh_mesh_to_world(voxmesh_mesh* mesh, const voxmesh_volume* volume);

/* NRRD (raw, host byte order) through a temporary renamed into place (voxmesh::write_nrrd). */
voxmesh_status voxmesh_write_nrrd(const char* path, const voxmesh_volume_view* volume);
voxmesh_status voxmesh_write_nrrd_to_memory(const voxmesh_volume_view* volume, const char* name,
                                            voxmesh_bytes** bytes);
/* The samples, valid until voxmesh_volume_free. */
voxmesh_volume_view voxmesh_volume_get_view(const voxmesh_volume* volume);
void voxmesh_volume_free(voxmesh_volume* volume);

/* ---- Sculpting (voxmesh::Sculpt, see voxmesh/sculpt.hpp): an editable copy of a volume
 * whose surface is kept as a mesh in blocks, so that an edit re-meshes only the blocks it can
 * change. Edits mark blocks dirty; voxmesh_sculpt_update re-meshes them. A sculpt is used from
 * one thread at a time. */
typedef struct voxmesh_sculpt voxmesh_sculpt;

typedef struct voxmesh_sculpt_options {
    double iso;            /* inside where value >= iso */
    unsigned threads;      /* update's worker threads; 0: the CPUs this process may use */
    size_t block_size;     /* cells per block side, 2..256 */
    int normals;           /* nonzero: per-vertex normals */
    int inside_below;      /* nonzero: inside where value < iso (winding and normals flip) */
    double strength_scale; /* field change of an add/subtract of strength 1; 0: 1, or the voxel
                              spacing for voxmesh_sculpt_from_mesh */
    int backend;           /* where update re-meshes: a voxmesh_backend, CPU, OPENCL or AUTO */
    int device;            /* OpenCL device index; -1: a GPU or accelerator, else the first */
} voxmesh_sculpt_options;
/* iso 0, threads 0, block_size 32, normals on, inside_below off, strength_scale 0, CPU, -1. */
voxmesh_sculpt_options voxmesh_default_sculpt_options(void);

/* A copy of `volume` (u8, u16 or f32 samples; convert others first). */
voxmesh_status voxmesh_sculpt_new(const voxmesh_volume_view* volume, const voxmesh_sculpt_options* options,
                                  voxmesh_sculpt** sculpt);
/* A closed model voxelized to a signed distance field (f32, positive inside, iso 0) in the
 * model's units. voxelize NULL: resolution 128, padding 2, band 4; its field must be
 * VOXMESH_FIELD_DISTANCE. More padding leaves a surface room to be built up before the
 * volume's border cuts it open. */
voxmesh_status voxmesh_sculpt_from_mesh(const voxmesh_mesh* model, const voxmesh_voxelize_options* voxelize,
                                        const voxmesh_sculpt_options* options, voxmesh_sculpt** sculpt);
/* A dims[0] x dims[1] x dims[2] volume of `type` (VOXMESH_U8, _U16 or _F32) filled with
 * f(x, y, z, user) at each sample's index coordinates, rounded and clamped for integer types.
 * f is called from several threads at once: it must be thread-safe. */
typedef double (*voxmesh_sample_function)(double x, double y, double z, void* user);
voxmesh_status voxmesh_sculpt_from_function(const size_t dims[3], int type, voxmesh_sample_function f, void* user,
                                            const voxmesh_sculpt_options* options, voxmesh_sculpt** sculpt);
void voxmesh_sculpt_free(voxmesh_sculpt* sculpt);

typedef enum voxmesh_brush {
    VOXMESH_BRUSH_ADD = 0,      /* value += strength * strength_scale * falloff */
    VOXMESH_BRUSH_SUBTRACT = 1, /* value -= strength * strength_scale * falloff */
    VOXMESH_BRUSH_SMOOTH = 2,   /* toward the mean of the 6 neighbours, strength 0..1 */
    VOXMESH_BRUSH_SET = 3       /* the box center +- radius := strength */
} voxmesh_brush;
typedef enum voxmesh_units {
    VOXMESH_UNITS_SAMPLES = 0, /* sample (index) coordinates */
    VOXMESH_UNITS_WORLD = 1    /* origin + index * spacing, radii in the same units */
} voxmesh_units;
/* One brush dab at `center` (x, y, z) with `radius`; see voxmesh::BrushOp. */
voxmesh_status voxmesh_sculpt_apply(voxmesh_sculpt* sculpt, int brush, const double center[3], double radius,
                                    double strength, int units);
/* Every sample with lo <= coordinate <= hi on each axis := value (clamped to the type). */
voxmesh_status voxmesh_sculpt_set_region(voxmesh_sculpt* sculpt, const double lo[3], const double hi[3],
                                         double value, int units);
/* The samples, writable: write through data, then call voxmesh_sculpt_invalidate_all (which
 * fails, marking nothing, where they now hold NaN or infinities). */
voxmesh_volume_view voxmesh_sculpt_get_view(const voxmesh_sculpt* sculpt);
void* voxmesh_sculpt_data(voxmesh_sculpt* sculpt);
voxmesh_status voxmesh_sculpt_invalidate_all(voxmesh_sculpt* sculpt);

typedef struct voxmesh_update_result {
    const size_t* changed; /* blocks re-meshed that are or were non-empty, ascending; valid until
                              the next update or voxmesh_sculpt_free */
    size_t changed_count;
    size_t remeshed;       /* dirty blocks re-meshed, empty ones included */
    double seconds;
} voxmesh_update_result;
/* Re-meshes the dirty blocks (result may be NULL). Out of memory leaves them dirty. */
voxmesh_status voxmesh_sculpt_update(voxmesh_sculpt* sculpt, voxmesh_update_result* result);
int voxmesh_sculpt_dirty(const voxmesh_sculpt* sculpt); /* nonzero: edits not yet meshed */
size_t voxmesh_sculpt_block_count(const voxmesh_sculpt* sculpt);
void voxmesh_sculpt_block_grid(const voxmesh_sculpt* sculpt, size_t grid[3]); /* blocks per axis */

/* One block's self-contained mesh (its own vertices; those on a face two blocks share are in
 * both). The arrays are valid until the next update or voxmesh_sculpt_free; NULL when empty. */
typedef struct voxmesh_block {
    size_t index;                 /* bx + nbx * (by + nby * bz) */
    size_t coord[3];              /* (bx, by, bz) */
    size_t cell_begin[3], cell_end[3];
    const float* positions;       /* xyz per vertex */
    const float* normals;         /* xyz per vertex; NULL when normals are off */
    const uint32_t* indices;      /* three per triangle, into this block's vertices */
    size_t vertex_count, triangle_count;
} voxmesh_block;
voxmesh_status voxmesh_sculpt_get_block(const voxmesh_sculpt* sculpt, size_t index, voxmesh_block* block);
/* Stroke scripts (see voxmesh/sculpt.hpp): one dab a line, "op x y z radius strength" with op
 * add | subtract | smooth | set; '#' starts a comment; a line "units world" or "units samples"
 * switches how later dabs are read. The whole script is read first, so a malformed line is
 * VOXMESH_ERROR "NAME:LINE: problem" with nothing applied. Then each dab is applied, the sculpt
 * updated, and on_frame (may be NULL) told, on the calling thread. */
typedef struct voxmesh_stroke_frame {
    size_t frame;          /* 0-based dab number */
    size_t line;           /* 1-based line of the script */
    int brush;             /* a voxmesh_brush */
    int units;             /* a voxmesh_units */
    double center[3], radius, strength;
    double edit_seconds, update_seconds; /* the dab's apply and update */
    size_t blocks_changed, blocks_remeshed;
} voxmesh_stroke_frame;
/* Returns 0 to go on; anything else stops the script after this frame, and the run returns
 * VOXMESH_ERROR naming the frame (the dabs so far stay applied and meshed). */
typedef int (*voxmesh_stroke_callback)(const voxmesh_stroke_frame* frame, void* user);
voxmesh_status voxmesh_sculpt_run_stroke_script(voxmesh_sculpt* sculpt, const char* path,
                                                voxmesh_stroke_callback on_frame, void* user);
/* The same with the script's `size` bytes in memory; `name` stands for the file in messages
 * (NULL: "strokes"). */
voxmesh_status voxmesh_sculpt_run_strokes(voxmesh_sculpt* sculpt, const char* text, size_t size, const char* name,
                                          voxmesh_stroke_callback on_frame, void* user);
/* The whole welded mesh, identical to voxmesh_extract of the samples (updates first). */
voxmesh_status voxmesh_sculpt_mesh(voxmesh_sculpt* sculpt, voxmesh_mesh** mesh);
/* Where update re-meshes: VOXMESH_BACKEND_CPU or _OPENCL, and "cpu" or the device's name. */
int voxmesh_sculpt_backend(const voxmesh_sculpt* sculpt);
const char* voxmesh_sculpt_device_name(const voxmesh_sculpt* sculpt);
/* Warnings so far (a fallback to the CPU), one a line; "" when none. Valid until the next call
 * on this sculpt. */
const char* voxmesh_sculpt_warnings(const voxmesh_sculpt* sculpt);

/* The message of the calling thread's last failed call ("" when none failed yet). Valid until
 * that thread's next call into voxmesh. */
const char* voxmesh_last_error(void);

/* "MAJOR.MINOR.PATCH" of the library linked. */
const char* voxmesh_version(void);

#ifdef __cplusplus
}
#endif

#endif /* VOXMESH_H */
