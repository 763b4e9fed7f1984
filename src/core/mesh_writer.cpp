#include "atomic_file.hpp"
#include "glb_writer.hpp"
#include "mesh_arrays.hpp"
#include "parallel.hpp"
#include "write_to_stream.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace voxmesh {

namespace {

using detail::write_bytes;

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

// Binary STL: 80-byte header, uint32 count, then per triangle a facet normal, 3 vertices and
// a 16-bit attribute, all little-endian (x86 and ARM hosts are little-endian).
// STL and the PLY header below name little-endian bytes and are written as the host's: a
// big-endian host would need a swap here, so it does not build instead of writing wrong files.
static_assert(std::endian::native == std::endian::little, "binary STL and PLY are written as the host's bytes");
void write_stl(std::FILE* f, const Mesh& mesh) {
    char header[80] = {};
    std::snprintf(header, sizeof header, "binary STL written by voxmesh %s", VOXMESH_VERSION_STRING);
    write_bytes(f, header, 80);
    const std::uint32_t count = static_cast<std::uint32_t>(mesh.triangle_count());
    write_bytes(f, &count, 4);
    std::vector<unsigned char> buffer;
    buffer.reserve(50 * 4096);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        const float* p[3];
        for (int k = 0; k < 3; ++k) p[k] = &mesh.positions[3 * static_cast<std::size_t>(mesh.indices[3 * t + k])];
        // In double: float edges of a model near ±FLT_MAX overflow, and the cross product of
        // tiny ones underflows; either way the facet normal came out zero.
        const double u[3] = {double(p[1][0]) - p[0][0], double(p[1][1]) - p[0][1], double(p[1][2]) - p[0][2]};
        const double v[3] = {double(p[2][0]) - p[0][0], double(p[2][1]) - p[0][1], double(p[2][2]) - p[0][2]};
        const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        const double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        float n[3];
        for (int k = 0; k < 3; ++k) n[k] = len > 0 ? static_cast<float>(c[k] / len) : 0.f;
        unsigned char record[50] = {};
        std::memcpy(record, n, 12);
        for (int k = 0; k < 3; ++k) std::memcpy(record + 12 + 12 * k, p[k], 12);
        buffer.insert(buffer.end(), record, record + 50);
        if (buffer.size() >= 50 * 4096) {
            write_bytes(f, buffer.data(), buffer.size());
            buffer.clear();
        }
    }
    write_bytes(f, buffer.data(), buffer.size());
}

std::size_t stl_bytes(const Mesh& mesh) { return 84 + 50 * mesh.triangle_count(); }

std::string ply_header(const Mesh& mesh) {
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by voxmesh " +
                         std::string(VOXMESH_VERSION_STRING) + "\nelement vertex " +
                         std::to_string(mesh.vertex_count()) + "\nproperty float x\nproperty float y\nproperty float z\n";
    if (!mesh.normals.empty()) header += "property float nx\nproperty float ny\nproperty float nz\n";
    return header + "element face " + std::to_string(mesh.triangle_count()) +
           "\nproperty list uchar uint vertex_indices\nend_header\n";
}

// Vertices as 3 (or 6, with normals) floats, faces as a count byte and 3 indices.
std::size_t ply_bytes(const Mesh& mesh) {
    return ply_header(mesh).size() + (mesh.positions.size() + mesh.normals.size()) * 4 + 13 * mesh.triangle_count();
}

void write_ply(std::FILE* f, const Mesh& mesh) {
    const bool normals = !mesh.normals.empty();
    const std::string header = ply_header(mesh);
    write_bytes(f, header.data(), header.size());
    std::vector<float> vertex_block;
    const std::size_t stride = normals ? 6 : 3;
    constexpr std::size_t kBatch = 8192;
    for (std::size_t v = 0; v < mesh.vertex_count(); v += kBatch) {
        const std::size_t n = std::min(kBatch, mesh.vertex_count() - v);
        vertex_block.resize(n * stride);
        for (std::size_t i = 0; i < n; ++i) {
            std::memcpy(&vertex_block[i * stride], &mesh.positions[3 * (v + i)], 12);
            if (normals) std::memcpy(&vertex_block[i * stride + 3], &mesh.normals[3 * (v + i)], 12);
        }
        write_bytes(f, vertex_block.data(), vertex_block.size() * sizeof(float));
    }
    std::vector<unsigned char> face_block;
    for (std::size_t t = 0; t < mesh.triangle_count(); t += kBatch) {
        const std::size_t n = std::min(kBatch, mesh.triangle_count() - t);
        face_block.resize(n * 13);
        for (std::size_t i = 0; i < n; ++i) {
            face_block[i * 13] = 3;
            std::memcpy(&face_block[i * 13 + 1], &mesh.indices[3 * (t + i)], 12);
        }
        write_bytes(f, face_block.data(), face_block.size());
    }
}

// Numbers as text by to_chars: the shortest form that reads back as the same float, and
// never the C locale's decimal comma (a GUI toolkit may have set one; printf would follow it).
// Each line is built in a local buffer and appended once: appending character by character
// took most of the time of an OBJ's face lines.
constexpr std::size_t kLineChars = 128;  // "vn" and 3 floats (<= 16 chars each), or "f" and 3 "i//i"

template <class Number>
char* put_number(char* at, Number value) {
    return std::to_chars(at, at + 32, value).ptr;
}

void append_triple(std::string& out, const char* tag, const float* v) {
    char line[kLineChars];
    char* at = line;
    for (const char* c = tag; *c; ++c) *at++ = *c;
    for (int k = 0; k < 3; ++k) {
        *at++ = ' ';
        at = put_number(at, v[k]);
    }
    *at++ = '\n';
    out.append(line, at);
}

void append_face(std::string& out, const std::uint32_t* corners, bool normals) {
    char line[kLineChars];
    char* at = line;
    *at++ = 'f';
    for (int k = 0; k < 3; ++k) {
        const std::uint64_t one_based = corners[k] + std::uint64_t{1};
        *at++ = ' ';
        at = put_number(at, one_based);
        if (normals) {
            *at++ = '/';
            *at++ = '/';
            at = put_number(at, one_based);
        }
    }
    *at++ = '\n';
    out.append(line, at);
}

// Writes lines 0..count-1, line(out, i) appending line i to `out`. Formatting numbers as text
// is most of an OBJ write's time, so it is done on all cores, in rounds of pieces of lines
// that the threads pull in order, and written in order: the same bytes as one thread gives.
// Writing a round to the file (a copy into the page cache, a third of the time) overlaps the
// formatting of the next: worker 0 writes the previous round, then pulls pieces too, so no
// thread waits for another.
// (STL's records, a facet normal each, are cheap to make: made so in blocks they wrote 15 %
// slower than in the small buffer that write_stl fills and writes while still in cache.)
template <class Line>
void write_lines(std::FILE* f, std::size_t count, const Line& line) {
    constexpr std::size_t kPiece = 1 << 12;          // lines; about 190 KB of text
    constexpr std::size_t kPiecesPerThread = 8;      // per round
    const std::size_t pieces = (count + kPiece - 1) / kPiece;
    const unsigned threads = static_cast<unsigned>(std::min<std::size_t>(detail::resolve_threads(0), pieces));
    const std::size_t per_round = std::max<std::size_t>(threads, 1) * kPiecesPerThread;
    std::array<std::vector<std::string>, 2> text{std::vector<std::string>(per_round), std::vector<std::string>(per_round)};
    const auto write_round = [&](const std::vector<std::string>& round) {
        for (const std::string& piece : round) write_bytes(f, piece.data(), piece.size());
    };
    std::size_t round = 0;
    for (std::size_t first_piece = 0; first_piece < pieces; first_piece += per_round, ++round) {
        std::vector<std::string>& now = text[round % 2];
        const std::vector<std::string>& before = text[(round + 1) % 2];
        const std::size_t in_round = std::min(per_round, pieces - first_piece);
        for (std::size_t p = in_round; p < per_round; ++p) now[p].clear();  // the last round's tail
        std::atomic<std::size_t> next{0};
        detail::run_workers(threads, [&](unsigned w) {
            if (w == 0 && round > 0) write_round(before);
            for (std::size_t p = next++; p < in_round; p = next++) {
                std::string& out = now[p];
                out.clear();
                const std::size_t begin = (first_piece + p) * kPiece, end = std::min(count, begin + kPiece);
                for (std::size_t i = begin; i < end; ++i) line(out, i);
            }
        });
    }
    if (round > 0) write_round(text[(round + 1) % 2]);
}

void write_obj(std::FILE* f, const Mesh& mesh) {
    const bool normals = !mesh.normals.empty();
    const std::string header = "# written by voxmesh " + std::string(VOXMESH_VERSION_STRING) + "\n";
    write_bytes(f, header.data(), header.size());
    write_lines(f, mesh.vertex_count(), [&](std::string& out, std::size_t v) {
        append_triple(out, "v", &mesh.positions[3 * v]);
    });
    if (normals)
        write_lines(f, mesh.vertex_count(), [&](std::string& out, std::size_t v) {
            append_triple(out, "vn", &mesh.normals[3 * v]);
        });
    write_lines(f, mesh.triangle_count(),
                [&](std::string& out, std::size_t t) { append_face(out, &mesh.indices[3 * t], normals); });
}

// A format's writer, bound to the mesh it writes, and the output's size where that is known
// before writing (0: not).
struct Writer {
    std::function<void(std::FILE*)> write;
    std::size_t bytes = 0;
};

// The writer of format `ext`, once `mesh` is known to be writable; Error naming `name` if not.
Writer checked_writer(const std::string& ext, const Mesh& mesh, const std::string& name) {
    if (ext != ".stl" && ext != ".ply" && ext != ".obj" && ext != ".glb")
        throw Error("cannot write '" + name + "': unknown mesh format '" + ext + "' (use .stl, .ply, .obj or .glb)");
    detail::check_mesh_arrays(mesh);
    // Before anything is sized or created (write_mesh_to_memory reserves 50 bytes a triangle).
    if (ext == ".stl" && mesh.triangle_count() > 0xffffffffull)
        throw Error("cannot write '" + name + "': " + std::to_string(mesh.triangle_count()) +
                    " triangles are more than binary STL's 32-bit count can hold (use .ply or .obj)");
    // "nan" and "inf" in a mesh file: most readers (ours included) refuse them.
    detail::check_finite_vertices(mesh.positions, "cannot write '" + name + "': ", "coordinate");
    detail::check_finite_vertices(mesh.normals, "cannot write '" + name + "': ", "normal");
    if (ext == ".stl") return {[&mesh](std::FILE* f) { write_stl(f, mesh); }, stl_bytes(mesh)};
    if (ext == ".ply") return {[&mesh](std::FILE* f) { write_ply(f, mesh); }, ply_bytes(mesh)};
    if (ext == ".obj") return {[&mesh](std::FILE* f) { write_obj(f, mesh); }, 0};
    // The JSON (the positions' bounds) is built once, for the size check and the write.
    std::string json = detail::glb_json(mesh);
    const std::uint64_t bytes =
        detail::checked_glb_bytes(mesh.vertex_count(), !mesh.normals.empty(), mesh.triangle_count(), json.size(), name);
    detail::check_glb_normals(mesh, name);
    return {[&mesh, json = std::move(json)](std::FILE* f) { detail::write_glb(f, mesh, json); },
            static_cast<std::size_t>(bytes)};
}

}  // namespace

void write_mesh(const std::string& path, const Mesh& mesh) {
    const Writer writer = checked_writer(lower_extension(path), mesh, path);
    detail::write_file_atomically(path, writer.write);
}

std::vector<unsigned char> write_mesh_to_memory(const Mesh& mesh, const std::string& name) {
    const Writer writer = checked_writer(lower_extension(name), mesh, name);
    return detail::write_to_memory(name, writer.write, writer.bytes);
}

void detail::write_mesh_to(std::FILE* file, const Mesh& mesh, const std::string& format, const std::string& name) {
    const Writer writer = checked_writer(format, mesh, name);
    detail::write_to_stream(file, name, writer.write);
}

}  // namespace voxmesh
