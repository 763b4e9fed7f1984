// Reading and writing volumes and meshes. Every reader checks its header against the file
// before allocating and throws voxmesh::Error whose message starts with the file's path
// ('path': problem). Nothing is allocated from an unchecked header field: the sample
// count is overflow-checked, compared with the file size (or, for gzip, the decompressed
// stream must be exactly as long as the header says; NIfTI's may go on past the samples), and
// refused when larger than the memory available.
//
// Samples: uncompressed data in host byte order at a suitably aligned offset is
// memory-mapped (Volume::storage owns the mapping; MAP_PRIVATE, so writes through
// Volume::data never reach the file; the file must not be truncated while the Volume
// lives). Data in the other byte order, misaligned, or compressed is copied into a heap
// block, as is a file that cannot be mapped (a filesystem without mmap). A volume with a
// flipped axis (see Geometry) is reversed in place after loading; for a mapped one that
// writes every page, so it costs as much memory as a copy.
//
// Geometry: a Volume has spacing and origin but no orientation; sample (i,j,k) lies at
// origin + (i,j,k) * spacing in the file's own world frame (NIfTI: RAS+, not converted to
// LPS). The direction of index axis a comes from NRRD `space directions`, MetaImage
// TransformMatrix, or NIfTI's sform (sform_code > 0) else qform (qform_code > 0, quaternion
// and qfac = pixdim[0] as in the NIfTI-1 standard). Spacing is the NRRD vector's length
// (or NRRD `spacings`), MetaImage ElementSpacing, the length of the NIfTI sform's column
// (sform) or pixdim (qform, or no transform). A NRRD without a space takes its origin (and,
// without `spacings`, its spacing) from `axis mins` and `axis maxs` as teem places samples:
// cell-centred (min + step / 2) unless `centers` says node.
// An axis whose direction points mostly along the negative of its own world axis (its largest
// component is that axis's and negative: e.g. the common NIfTI sform diag(-2, 2, 2), also
// slightly oblique) is "flipped": its samples are reversed on load and the origin moved
// to the grid's minimum corner (origin_a - spacing_a * (n_a - 1)), so every sample keeps
// its position and meshes land where the file says, unmirrored. VolumeInfo::flipped says
// which axes. A negative spacing (NRRD `spacings`, MetaImage ElementSpacing,
// RawLayout::spacing) runs its axis the other way and is flipped alike; the sign of NIfTI's
// pixdim[1..3] is ignored, its magnitude being the spacing (as nibabel fixes it; nifti1_io's
// qform takes a pixdim <= 0 as 1), and a pixdim of 0 or not finite, where used, is 1 (as
// nifti1_io reads it, and nibabel a 0). The rest of a direction (an oblique axis's off-axis
// part, a rotation, an axis permutation, which is never flipped) is not applied to the
// samples: the axis keeps its spacing (the direction's length) and the origin as written,
// apart from the flip, and VolumeInfo::rotation_dropped says so. It is kept as the volume's
// world transform instead (to_world places a mesh with it):
//   world(i,j,k) = world_origin + D * ((i,j,k) * spacing)     (i,j,k: the loaded Volume's index)
// D (VolumeInfo::directions) has the unit direction of loaded index axis a as column a: the
// file's direction for axis a (NRRD vector, sform column, qform rotation column, MetaImage
// TransformMatrix column) divided by its length, as spacing gives the length (a NRRD space of
// more than three dimensions keeps the first three components), negated for a flipped axis,
// whose samples now run the other way. world_origin is where loaded sample (0,0,0) lies: for
// the file's origin O and unit directions u_a (before negation),
//   world_origin = O + sum over flipped a of u_a * spacing_a * (n_a - 1)
// (the file's last sample along a is the loaded first). A volume without rotation_dropped has
// D = identity and world_origin = origin exactly (an off-axis part within header noise,
// 1e-6 of the length, is dropped as before), so to_world changes nothing; so do directions
// that do not span 3-D (a NRRD space of 2 dimensions), which are dropped as before.
//
// NIfTI scl_slope / scl_inter are NOT applied: the samples keep their stored type and
// values (so they can be mapped, and an iso value means the same as in other tools that
// read stored values). VolumeInfo::value_scale / value_offset report them; a physical
// value is stored * value_scale + value_offset, so the stored iso for a physical one is
// (physical - value_offset) / value_scale.
//
// Dimensions: volumes are 3-D. A 4-D (or higher) NRRD/MetaImage/NIfTI whose extra axes all
// have size 1 is accepted as 3-D; anything else is an error. MetaImage's and NIfTI's extra
// axes follow the three spatial ones; a NRRD's or NumPy array's may lie anywhere (NRRD
// `sizes: 1 4 3 2`, NumPy (z, y, x, 1)), as dropping them leaves the samples' order. NRRD
// `kinds`: the three axes kept must be domain, space or unknown (??? / none); a colour,
// vector, tensor, list or time axis is an error, unless of size 1 and so dropped.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <array>
#include <cstddef>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace voxmesh {

// Headerless samples: the caller says what they are. The file must hold exactly
// offset + nx*ny*nz*scalar_size bytes.
struct RawLayout {
    std::array<std::size_t, 3> dims{0, 0, 0};
    ScalarType type = ScalarType::U8;
    bool big_endian = false;
    std::size_t offset = 0;  // bytes to skip before the first sample
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};
};
Volume read_raw(const std::string& path, const RawLayout& layout);
// The same samples from a stream (a pipe, stdin): `offset` bytes are skipped, then exactly
// nx*ny*nz*scalar_size bytes are read into memory (checked against the memory available
// first), and the stream must end there. Errors name `name`; they are voxmesh::Error whatever
// the stream's exception mask, which is kept.
Volume read_raw(std::istream& in, const std::string& name, const RawLayout& layout);

// What a volume file holds, read from its header only.
struct VolumeInfo {
    std::string format;  // "nrrd", "metaimage", "nifti", "vtk", "npy", "raw"
    ScalarType type = ScalarType::U8;
    std::array<std::size_t, 3> dims{0, 0, 0};
    std::array<double, 3> spacing{1, 1, 1};
    std::array<double, 3> origin{0, 0, 0};  // the minimum corner, after flips (see Geometry)
    // Axes stored in the negative direction, reversed on load (see Geometry).
    std::array<bool, 3> flipped{false, false, false};
    // The direction matrix is not diagonal (a rotation, an axis permutation, an oblique axis):
    // the samples stay in index axes, and `directions` / `world_origin` hold it (see Geometry).
    bool rotation_dropped = false;
    std::string encoding;     // "raw", "gzip" (zlib streams, as in MetaImage, count as "gzip"), "ascii" (legacy VTK)
    bool big_endian = false;  // byte order of the stored samples
    std::size_t file_bytes = 0;  // size of the file named (the header for .nhdr / .mhd)
    std::string data_file;       // the file holding the samples (== path when attached)
    // Stored-to-physical value mapping (NIfTI scl_slope/scl_inter); 1 and 0 elsewhere.
    double value_scale = 1;
    double value_offset = 0;
    // NRRD "key:=value" lines, unescaped (e.g. what write_nrrd was given); empty for other formats.
    std::map<std::string, std::string> key_values;
    // The world transform of the loaded Volume: sample (i,j,k) lies at
    // world_origin + D * ((i,j,k) * spacing), D[c][a] = directions[3 * c + a] (column a: loaded
    // index axis a's unit direction). Identity and `origin` unless rotation_dropped.
    std::array<double, 9> directions{1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::array<double, 3> world_origin{0, 0, 0};
    // (Last, so that the fields before them keep their places for code built against 0.1.0.)
};

// Moves a mesh extracted from the Volume `info` describes (positions origin + index * spacing,
// as extract places them) into the file's world frame (see Geometry): positions by the affine,
// normals by the inverse-transpose of `directions` (renormalised, so still unit and outward),
// and, where its determinant is negative (a mirroring), every triangle's winding reversed so
// that it stays counter-clockwise seen from outside. Nothing changes where the transform is
// the identity (no rotation_dropped). Throws Error, leaving the mesh as it was, for arrays
// that are not whole triples, normals for a different number of vertices, a singular or
// non-finite transform, a non-finite position, and a transform that would put a position
// beyond the float range (a far world_origin: floats would turn it into inf).
void to_world(Mesh& mesh, const VolumeInfo& info);
// Whether to_world moves a mesh of the Volume `info` describes: false where the world transform
// is the loaded samples' own placement (`directions` the identity, `world_origin` the origin):
// without rotation_dropped, and where dropped directions do not span 3-D (to_world cannot
// place them either).
bool has_world_transform(const VolumeInfo& info);

// The iso voxmesh recorded for meshing a volume it wrote: the NRRD line "voxmesh_iso:=value"
// (`voxmesh voxelize` writes 0 for a distance field and 127.5 for occupancy, voxmesh-bench
// --write-volume its field's iso). nullopt where the file has no such line; an Error naming
// `name` where the value is not one finite number ("", "1abc", "nan", "inf").
inline constexpr const char* kRecordedIsoKey = "voxmesh_iso";
std::optional<double> recorded_iso(const VolumeInfo& info, const std::string& name);

// NRRD (.nrrd, .nhdr), MetaImage (.mhd, .mha), NIfTI-1 (.nii, .nii.gz), legacy VTK (.vtk),
// NumPy (.npy), chosen by extension (case-insensitive). A .nii that is gzip-compressed is detected by content.
// Legacy VTK: DATASET STRUCTURED_POINTS (DIMENSIONS, SPACING or ASPECT_RATIO, ORIGIN; a
// negative spacing flips its axis) whose POINT_DATA's first SCALARS or COLOR_SCALARS (unsigned
// char; ASCII writes byte b as b/255) of one component, or a FIELD's first array, is the
// volume (VECTORS, NORMALS, ... before it are skipped); BINARY (big-endian, copied) or ASCII (numbers that must fit the type); arrays
// after it are ignored. read_volume_info checks ASCII data only for length.
// NIfTI-1: one file (magic n+1; a .hdr/.img pair is refused), its byte order told by
// sizeof_hdr; dim[1..dim[0]] must be at least 1 (nifti1_io takes 0 as 1, nibabel as an empty
// axis); bitpix must agree with datatype; vox_offset a whole number >= 348; bytes after the
// samples (in a .nii.gz's stream too) are ignored, as nibabel and nifti1_io do; the sform or
// qform used must be finite (nibabel's affine would be NaN).
// NRRD: 'line skip' then 'byte skip' (-1: samples end the file; raw only) as teem applies
// them, from the data file's start or, for attached data, from just past the blank line.
// MetaImage: ElementDataFile LOCAL (also Local, local, as MetaIO) or one data file; HeaderSize
// bytes are skipped from the start of the file holding the samples, a LOCAL .mha too (as
// MetaIO seeks), or -1 for samples at its end.
// NumPy: numpy.save's format 1.0 to 3.0 of a 3-D array (axes of size 1 beyond those allowed):
// [z, y, x] in C order, [x, y, z] in Fortran order, so that x varies fastest either way; bool
// (read as u8 0 and 1), 8/16/32-bit integers, float32 or float64 in either byte order; spacing
// 1 and origin 0, as the format has no geometry.
Volume read_volume(const std::string& path);
VolumeInfo read_volume_info(const std::string& path);
// read_volume, also filling `info` as read_volume_info would, from the one reading of the header.
Volume read_volume(const std::string& path, VolumeInfo& info);
// The same checks as read_raw, without loading the samples.
VolumeInfo read_raw_info(const std::string& path, const RawLayout& layout);
// read_raw, also filling `info` (format "raw", flipped axes, ...) as read_volume(path, info) does.
Volume read_raw(const std::string& path, const RawLayout& layout, VolumeInfo& info);

// NRRD with raw encoding in host byte order (spacing and origin written as `space
// directions` / `space origin` with `space dimension: 3`), through a temporary file renamed
// into place (through a symbolic link, keeping a replaced file's permission bits, as
// write_mesh).
// `key_values` become "key:=value" lines that read back exactly (a backslash is doubled, as
// NRRD escapes it; read_volume takes a backslash-n and a doubled backslash back as teem does):
// a key is non-empty, does not start with '#' and holds no ":=" or ": ", neither holds '\r' or
// '\n', and the header stays within the 1 MiB the reader reads (an Error otherwise).
// Refused (Error): an empty volume, spacing zero or not finite, an origin not finite, and
// samples placed beyond the float range, which read_volume would refuse to read back.
void write_nrrd(const std::string& path, const VolumeView& volume,
                const std::map<std::string, std::string>& key_values = {});
// The bytes write_nrrd would write, in memory; `name` names the output in errors.
std::vector<unsigned char> write_nrrd_to_memory(const VolumeView& volume, const std::string& name,
                                                const std::map<std::string, std::string>& key_values = {});

// STL, binary or ASCII (binary when 84 + 50*n == file size, whatever the header says),
// welded by exact float position (-0 and +0 are one position): positions and indices
// filled, normals empty. Triangles keep the file's order and winding; non-finite
// coordinates are an error, and so is an ASCII number beyond the float range (one too small
// for a float reads as 0). No triangles (an 84-byte binary file, "solid"/"endsolid") is an
// empty mesh, as write_mesh writes one. ASCII lines may end in "\n", "\r\n" or a lone "\r",
// after a UTF-8 byte order mark or none.
Mesh read_stl(const std::string& path);
// PLY: ascii, binary_little_endian or binary_big_endian 1.0. The "vertex" element's x, y, z
// (any PLY scalar type, read as float) become positions, and its nx, ny, nz normals where all
// three are present (left empty, as read_obj leaves them, when one is NaN or infinite);
// other properties and elements are skipped. The "face" element's list
// "vertex_indices" (or "vertex_index") becomes triangles: polygons are fanned from their
// first corner, keeping the file's order and winding. Vertices are kept as the file indexes
// them (not welded). A file with vertices and no faces (a point cloud) reads as vertices with
// no triangles. Element counts are checked against the file's size before anything is
// allocated; a face with fewer than three corners, an index outside the vertices, and a
// non-finite or beyond-float coordinate are errors. Header lines end in "\n", "\r\n" or, when
// the first line does, a lone "\r"; a UTF-8 byte order mark before "ply" is skipped.
Mesh read_ply(const std::string& path);
// Wavefront OBJ: "v x y z" positions (a w or r g b [a] after them is ignored) and "f" faces
// (v, v/vt, v/vt/vn, v//vn; negative indices count back from the latest item), polygons
// fanned from their first corner in the file's order and winding; vertices kept as the file
// indexes them (not welded). Normals are filled only where the file has one finite "vn" per
// "v" and every corner names the normal of its own vertex (as write_mesh writes them);
// otherwise they are left empty. Other statements (vt, vp, o, g, s, usemtl, mtllib, l, p,
// free-form geometry's and unknown ones) are skipped; '#' comments end with their line, and a '\' ending a line
// continues the statement; lines end in "\n", "\r\n" or a lone "\r", and a UTF-8 byte order
// mark before the first is skipped. Errors name the line: a face with fewer than three corners, an
// index 0 or beyond the items read so far (no forward references), a malformed corner, a
// non-finite or beyond-float coordinate, and a file without faces that holds a statement
// OBJ does not have (other text, not a model). Without faces it is otherwise vertices with no
// triangles (write_mesh's empty mesh, a point cloud), as in read_ply.
Mesh read_obj(const std::string& path);
// read_stl, read_ply or read_obj, chosen by the extension (.stl, .ply, .obj; any case). In
// each, a file of no bytes at all is an Error, not an empty mesh.
Mesh read_mesh(const std::string& path);

// Reading from memory: the readers above over `size` bytes at `data` (a download, a blob from
// a database, a file read whole), with no file involved. `name` stands for the file's path: its
// extension picks the format as read_volume's and read_mesh's does ("scan.nii.gz", "part.stl"),
// and errors start with 'name':. The same checks apply, with `size` as the file's size. The
// bytes are only read, and not used after the call: a Volume holds its own copy of the samples
// (never a view of `data`). A header that names a separate data file (.nhdr or .mhd with
// 'data file' / ElementDataFile) is an Error, as there is no directory to look in.
Volume read_volume_from_memory(const void* data, std::size_t size, const std::string& name);
Volume read_volume_from_memory(const void* data, std::size_t size, const std::string& name, VolumeInfo& info);
// The same with the bytes handed over: where a file would be mapped (raw samples in host byte
// order, aligned), the Volume keeps the vector and uses its samples where they lie, with no
// copy (axes flipped in place); otherwise it is freed once read. `bytes` is left empty.
Volume read_volume_from_memory(std::vector<unsigned char>&& bytes, const std::string& name);
Volume read_volume_from_memory(std::vector<unsigned char>&& bytes, const std::string& name, VolumeInfo& info);
VolumeInfo read_volume_info_from_memory(const void* data, std::size_t size, const std::string& name);
Volume read_raw_from_memory(const void* data, std::size_t size, const std::string& name, const RawLayout& layout);
Mesh read_mesh_from_memory(const void* data, std::size_t size, const std::string& name);

}  // namespace voxmesh
