#include "atomic_file.hpp"

#include <voxmesh/voxmesh.hpp>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace voxmesh::detail {

void write_bytes(std::FILE* file, const void* data, std::size_t bytes) {
    if (bytes && std::fwrite(data, 1, bytes, file) != bytes) throw Error(std::string("write failed: ") + std::strerror(errno));
}

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    std::error_code ec;
    if (fs::is_directory(target, ec)) throw Error("cannot write '" + path + "': it is a directory");
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir, ec)) throw Error("cannot write '" + path + "': directory '" + dir.string() + "' does not exist");

    // Built with append: gcc 12 gives a false -Wrestrict on operator+ chains here.
    std::string name = ".";
    name.append(target.filename().string()).append(".tmpXXXXXX");
    std::string temp = (dir / name).string();
    const int fd = mkstemp(temp.data());
    if (fd < 0) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    std::FILE* file = fdopen(fd, "wb");
    if (!file) {
        ::close(fd);
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    }
    try {
        write(file);
        if (std::fflush(file) != 0 || ::fsync(fileno(file)) != 0) throw Error(std::string("write failed: ") + std::strerror(errno));
    } catch (const std::exception& e) {
        std::fclose(file);
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + e.what());
    }
    if (std::fclose(file) != 0) {
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    }
    ::chmod(temp.c_str(), 0644);
    if (std::rename(temp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(err));
    }
}

}  // namespace voxmesh::detail
