#include "stdin_input.hpp"

#include "core/exit_signals.hpp"

#include "io/inflate.hpp"
#include "io/readers.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

namespace voxmesh::cli {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kHeadBytes = 64 * 1024;  // enough for any header the sniffing reads

bool starts_with(const std::string& s, const std::string& prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

// The first word of the first line that is not blank and not a '#' comment ("" if none).
std::string first_word(const std::string& head, bool hash_comments) {
    std::istringstream lines(head);
    std::string line;
    while (std::getline(lines, line)) {
        const std::size_t at = line.find_first_not_of(" \t\r");
        if (at == std::string::npos || (hash_comments && line[at] == '#')) continue;
        const std::size_t end = line.find_first_of(" \t\r=", at);
        return line.substr(at, end == std::string::npos ? std::string::npos : end - at);
    }
    return {};
}

bool is_metaimage_key(const std::string& word) {
    static const char* const keys[] = {"ObjectType",     "ObjectSubType",   "NDims",           "DimSize",
                                       "ElementType",    "ElementSpacing",  "ElementDataFile", "BinaryData",
                                       "BinaryDataByteOrderMSB", "ElementByteOrderMSB", "CompressedData",
                                       "TransformMatrix", "Offset",         "Position",        "Comment",
                                       "HeaderSize",     "AnatomicalOrientation", "CenterOfRotation"};
    return std::any_of(std::begin(keys), std::end(keys), [&](const char* k) { return word == k; });
}

bool is_obj_keyword(const std::string& word) {
    static const char* const keys[] = {"v", "vt", "vn", "vp", "f", "l", "p", "o", "g", "s", "mtllib", "usemtl"};
    return std::any_of(std::begin(keys), std::end(keys), [&](const char* k) { return word == k; });
}

// A binary STL: 80 header bytes, a little-endian triangle count, 50 bytes per triangle.
bool is_binary_stl(const std::string& head, std::size_t size) {
    if (head.size() < 84 || size < 84) return false;
    std::uint32_t count = 0;
    for (int i = 3; i >= 0; --i) count = count << 8 | static_cast<unsigned char>(head[80 + static_cast<std::size_t>(i)]);
    return (size - 84) % 50 == 0 && (size - 84) / 50 == count;
}

std::string kind_text(InputKind kind) {
    switch (kind) {
        case InputKind::Volume: return "a volume (NRRD, NIfTI-1, MetaImage .mha, legacy VTK, NumPy .npy; raw samples with --dims and --type)";
        case InputKind::Model: return "a model (STL, PLY, OBJ)";
        case InputKind::VolumeOrModel: return "a volume (NRRD, NIfTI-1, MetaImage .mha, legacy VTK, NumPy .npy) or a model (STL, PLY, OBJ)";
        case InputKind::Raw: return "raw samples";
        case InputKind::Text: return "text";
    }
    return "";
}

// Copies all of file descriptor `in` into `path`; false with errno set on failure, and
// read_failed set where reading `in` failed (not the copy).
bool copy_all(int in, const std::string& path, std::size_t& copied, bool& read_failed) {
    read_failed = false;
    const int out = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);  // made by make_temp_file
    if (out < 0) return false;
    std::vector<char> buffer(1 << 20);
    copied = 0;
    for (;;) {
        const ssize_t got = ::read(in, buffer.data(), buffer.size());
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) {
            read_failed = true;  // standard input itself (a directory, a read error), not the copy
            break;
        }
        if (got == 0) return ::close(out) == 0;
        for (ssize_t done = 0; done < got;) {
            const ssize_t put = ::write(out, buffer.data() + done, static_cast<std::size_t>(got - done));
            if (put < 0 && errno == EINTR) continue;
            if (put < 0) {
                const int err = errno;
                ::close(out);
                errno = err;
                return false;
            }
            done += put;
        }
        copied += static_cast<std::size_t>(got);
    }
    const int err = errno;
    ::close(out);
    errno = err;
    return false;
}

// Whether gzip-compressed `head` (the start of a stream) inflates to a NIfTI-1 header:
// sizeof_hdr 348 in either byte order. True where it cannot tell (the reader then says why).
bool gzip_holds_nifti(const std::string& head) {
    unsigned char header[4] = {};
    try {
        io::Inflater inflater(kStdinName, reinterpret_cast<const unsigned char*>(head.data()), head.size());
        if (inflater.read(header, sizeof header) < sizeof header) return true;
    } catch (const std::exception&) {
        return true;
    }
    const auto le = static_cast<std::uint32_t>(header[0] | header[1] << 8 | header[2] << 16 | std::uint32_t{header[3]} << 24);
    const auto be = static_cast<std::uint32_t>(header[3] | header[2] << 8 | header[1] << 16 | std::uint32_t{header[0]} << 24);
    return le == 348 || be == 348;
}

std::string read_head(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string head(kHeadBytes, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    return head;
}

}  // namespace

std::string sniff_format(const std::string& head, std::size_t size, InputKind kind) {
    if (kind == InputKind::Raw) return ".raw";
    if (kind == InputKind::Text) return ".txt";
    const bool volume = kind != InputKind::Model, model = kind != InputKind::Volume;
    if (volume) {
        if (starts_with(head, "NRRD000")) return ".nrrd";
        // Any case, as the VTK reader takes its version line.
        std::string first(head.substr(0, 14));
        std::transform(first.begin(), first.end(), first.begin(), [](unsigned char c) { return std::tolower(c); });
        if (first == "# vtk datafile") return ".vtk";
        if (starts_with(head, std::string("\x93NUMPY", 6))) return ".npy";
        if (head.size() >= 2 && static_cast<unsigned char>(head[0]) == 0x1f && static_cast<unsigned char>(head[1]) == 0x8b)
            return ".nii.gz";
        if (head.size() >= 348 && head.compare(344, 4, std::string("n+1\0", 4)) == 0) return ".nii";
    }
    if (model) {
        if (starts_with(head, "ply\n") || starts_with(head, "ply\r\n")) return ".ply";
        if (is_binary_stl(head, size)) return ".stl";
        if (first_word(head, false) == "solid") return ".stl";
    }
    if (volume && is_metaimage_key(first_word(head, false))) return ".mha";
    if (model && is_obj_keyword(first_word(head, true))) return ".obj";
    return {};
}

namespace {

// TMPDIR, or /tmp where it is unset or empty (as mktemp(1) takes it). Not
// fs::temp_directory_path(): it throws a filesystem_error (an "internal error", exit 1) for a
// TMPDIR that is empty or names no directory, where mkostemps names the problem below.
std::string temp_directory() {
    const char* dir = std::getenv("TMPDIR");
    return dir && *dir ? dir : "/tmp";
}

// A new empty temporary in TMPDIR ending in `suffix`, listed in `listed` for the signal handler
// before any signal can end the program (none is delivered between creating and listing it);
// BadInput on failure.
std::string make_temp_file(const std::string& suffix, voxmesh::detail::ListedTemporary& listed) {
    const voxmesh::detail::ExitSignalsHeld held;
    const std::string dir = temp_directory();
    std::string pattern = (fs::path(dir) / "voxmesh-stdin-XXXXXX").string() + suffix;
    const int fd = ::mkostemps(pattern.data(), static_cast<int>(suffix.size()), O_CLOEXEC);
    if (fd < 0)
        throw BadInput(std::string("cannot make a temporary file for ") + kStdinName + " in '" + dir +
                       "' (TMPDIR): " + std::strerror(errno));
    ::close(fd);
    listed.list(pattern);
    return pattern;
}

}  // namespace

InputPath::InputPath(const std::string& arg, InputKind kind) : path_(arg), display_(arg) {
    if (arg != "-") {
        check_input_file(arg);
        return;
    }
    display_ = kStdinName;
    if (::isatty(STDIN_FILENO))
        throw BadInput(std::string(kStdinName) + " is a terminal: pipe or redirect " + kind_text(kind) + " into it");
    // Copied first, then named: the format is told from the content.
    const std::string spooled = make_temp_file("", copy_listed_);
    path_ = spooled;
    spooled_ = true;  // from here the destructor's to remove, so the constructor cleans up on throw
    try {
        std::size_t size = 0;
        bool read_failed = false;
        if (!copy_all(STDIN_FILENO, spooled, size, read_failed)) {
            if (read_failed) throw BadInput(std::string("cannot read ") + kStdinName + ": " + std::strerror(errno));
            throw BadInput(std::string("cannot copy ") + kStdinName + " to '" + spooled + "': " + std::strerror(errno));
        }
        if (size == 0) throw BadInput(std::string("'") + kStdinName + "': is empty");
        const std::string head = read_head(spooled);
        const std::string ext = sniff_format(head, size, kind);
        if (ext.empty())
            throw BadInput(std::string("'") + kStdinName + "': not " + kind_text(kind) + " by its first bytes");
        // Of gzip-compressed files only .nii.gz is read whole; another (a .nrrd.gz, a .stl.gz)
        // was refused as "sizeof_hdr is ..., not a NIfTI-1 file".
        if (ext == ".nii.gz" && !gzip_holds_nifti(head))
            throw BadInput(std::string("'") + kStdinName +
                           "': gzip-compressed, and not a NIfTI-1 header inside (the one compressed format read "
                           "whole); decompress it first, e.g. gunzip -c FILE | voxmesh ...");
        const std::string named = make_temp_file(ext, named_listed_);
        if (::rename(spooled.c_str(), named.c_str()) != 0) {
            const int err = errno;
            ::unlink(named.c_str());
            named_listed_.unlist();
            throw BadInput(std::string("cannot rename the copy of ") + kStdinName + ": " + std::strerror(err));
        }
        copy_listed_.unlist();
        path_ = named;
        // A header whose samples are in a file of their own names it beside itself; beside the
        // spooled copy there is nothing.
        if (ext == ".nrrd" || ext == ".mha") {
            const std::string data = read([&] {
                const io::InputFile file(path_);
                return (ext == ".nrrd" ? io::read_nrrd_header(file) : io::read_metaimage_header(file)).layout.data_path;
            });
            if (data != path_)
                throw BadInput(std::string("'") + kStdinName + "': the header names a separate data file ('" +
                               fs::path(data).filename().string() +
                               "'), which cannot be found from standard input; give the header's path instead");
        }
    } catch (...) {
        remove_spool();
        throw;
    }
}

InputPath::~InputPath() { remove_spool(); }

void InputPath::remove_spool() noexcept {
    if (!spooled_) return;
    ::unlink(path_.c_str());  // a mapped Volume keeps its pages after the file is gone
    copy_listed_.unlist();
    named_listed_.unlist();
    spooled_ = false;
}

std::string InputPath::shown(std::string text) const {
    if (!spooled_) return text;
    for (std::size_t at = text.find(path_); at != std::string::npos; at = text.find(path_, at + display_.size()))
        text.replace(at, path_.size(), display_);
    return text;
}

Mesh load_model(const std::string& arg, const std::string& command) {
    const InputPath input(arg, InputKind::Model);
    if (arg != "-") check_model_extension(arg, command);
    return input.read([&] { return read_mesh(input.path()); });
}

}  // namespace voxmesh::cli
