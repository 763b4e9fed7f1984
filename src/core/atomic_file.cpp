#include "atomic_file.hpp"

#include <voxmesh/voxmesh.hpp>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <new>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace voxmesh::detail {

void write_bytes(std::FILE* file, const void* data, std::size_t bytes) {
    if (bytes && std::fwrite(data, 1, bytes, file) != bytes) throw Error(std::string("write failed: ") + std::strerror(errno));
}

namespace {

// The temporaries listed, for remove_partial_outputs() to find from a signal handler: fixed
// slots, lock-free flags, no allocation. More temporaries at once than slots go unlisted.
struct InFlight {
    std::atomic<bool> taken{false};  // the slot belongs to a ListedTemporary
    std::atomic<bool> ready{false};  // `path` is complete and names its temporary
    char path[4096];
};
InFlight g_in_flight[16];
static_assert(std::atomic<bool>::is_always_lock_free);

// "cannot write 'name': ..." for what a write threw; running out of memory stays an
// OutOfMemoryError.
[[noreturn]] void throw_write_failure(const std::string& name, const std::exception& e) {
    if (dynamic_cast<const std::bad_alloc*>(&e) || dynamic_cast<const OutOfMemoryError*>(&e))
        throw OutOfMemoryError("cannot write '" + name + "': out of memory");
    throw Error("cannot write '" + name + "': " + e.what());
}

}  // namespace

ListedTemporary::~ListedTemporary() { unlist(); }

void ListedTemporary::list(const std::string& temp) {
    if (temp.size() >= sizeof(InFlight::path)) return unlist();
    auto* slot = static_cast<InFlight*>(slot_);
    if (!slot) {
        for (InFlight& candidate : g_in_flight) {
            bool expected = false;
            if (candidate.taken.compare_exchange_strong(expected, true)) {
                slot = &candidate;
                break;
            }
        }
        if (!slot) return;
        slot_ = slot;
    }
    slot->ready.store(false, std::memory_order_release);
    std::memcpy(slot->path, temp.c_str(), temp.size() + 1);
    slot->ready.store(true, std::memory_order_release);
}

void ListedTemporary::unlist() {
    auto* slot = static_cast<InFlight*>(slot_);
    if (!slot) return;
    slot->ready.store(false, std::memory_order_release);
    slot->taken.store(false, std::memory_order_release);
    slot_ = nullptr;
}

namespace {

// A new temporary next to the target, created as any new file is (0666 less the umask):
// mkstemp makes it 0600, and a fixed chmod afterwards would ignore the umask. pid and a
// counter make the name unique; one left by a crashed process of the same pid is skipped
// (a signal while its name is listed would remove it: it is a leftover temporary too).
// Only the first 200 bytes of a long name are used, so that the temporary's name stays within
// NAME_MAX (255) where the target's does.
int create_temp(const std::filesystem::path& dir, const std::string& filename, std::string& temp, ListedTemporary& listed,
                mode_t mode) {
    static std::atomic<unsigned> counter{0};
    for (int attempt = 0; attempt < 1000; ++attempt) {
        // Built with append: gcc 12 gives a false -Wrestrict on operator+ chains here.
        std::string name = ".";
        name.append(filename, 0, 200).append(".tmp").append(std::to_string(::getpid())).append("-");
        name.append(std::to_string(counter++));
        temp = (dir / name).string();
        listed.list(temp);
        const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        if (fd >= 0 || errno != EEXIST) return fd;
    }
    return -1;  // errno is EEXIST
}

// `path`, or where its chain of symbolic links ends: a write replaces the file a link names
// and keeps the link, as a shell's `>` writes through it (a rename onto the link itself would
// put a file in its place and leave its target as it was).
std::string followed_path(const std::string& path) {
    namespace fs = std::filesystem;
    fs::path p(path);
    for (int hops = 0; hops < 40; ++hops) {  // Linux's own limit
        std::error_code ec;
        if (!fs::is_symlink(p, ec)) return p.string();
        const fs::path link = fs::read_symlink(p, ec);
        if (ec) throw Error("cannot write '" + path + "': " + ec.message());
        p = link.is_absolute() ? link : p.parent_path() / link;
    }
    throw Error("cannot write '" + path + "': too many levels of symbolic links");
}

}  // namespace

std::filesystem::path target_directory(const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    std::error_code ec;
    if (fs::is_directory(target, ec)) throw Error("cannot write '" + path + "': it is a directory");
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(dir, ec)) throw Error("cannot write '" + path + "': directory '" + dir.string() + "' does not exist");
    return dir;
}

namespace {

// A FIFO, a device or a socket is written into, as a shell's `>` writes into it: a rename
// would put a regular file in its place (an out.ply linked to /dev/null, written through, would
// have replaced /dev/null itself when run as root).
void write_into_special_file(const std::string& path, const std::string& destination,
                             const std::function<void(std::FILE*)>& write) {
    const int fd = ::open(destination.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    std::FILE* file = fdopen(fd, "wb");
    if (!file) {
        ::close(fd);
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    }
    try {
        write_to_stream(file, path, write);
    } catch (...) {
        std::fclose(file);
        throw;
    }
    if (std::fclose(file) != 0) throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

}  // namespace

namespace {

// Where a write of `path` goes, and what is there now.
struct Destination {
    std::string path;               // `path` with its symbolic links followed
    std::filesystem::path dir;      // where the temporary is made
    bool exists = false;
    struct stat existing {};
};

// The checks a write makes before it creates anything; throws Error naming `path`.
Destination destination_of(const std::string& path) {
    // The kernel follows a link first, so that its own refusals hold as for `>`: with
    // fs.protected_symlinks, a link in a sticky world-writable directory (/tmp) owned by another
    // user is not followed, and resolving it here would have replaced the file it names.
    if (std::error_code ec; std::filesystem::is_symlink(path, ec)) {
        const int fd = ::open(path.c_str(), O_PATH | O_CLOEXEC);
        if (fd >= 0) ::close(fd);
        else if (errno == EACCES) throw Error("cannot write '" + path + "': " + std::strerror(errno) +
                                              " (the system refuses to follow this symbolic link)");
    }
    Destination d;
    d.path = followed_path(path);
    d.dir = target_directory(d.path);
    d.exists = ::stat(d.path.c_str(), &d.existing) == 0;
    // A file this process may not write is refused, as `>` refuses it, though the directory
    // would let a rename replace it.
    if (d.exists && S_ISREG(d.existing.st_mode) && ::faccessat(AT_FDCWD, d.path.c_str(), W_OK, AT_EACCESS) != 0)
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    // In a sticky directory (/tmp) only the file's or the directory's owner may rename over
    // it (root too, by CAP_FOWNER, which this does not ask the kernel about: it only refuses
    // earlier what the rename would refuse after the work).
    struct stat dir {};
    if (d.exists && S_ISREG(d.existing.st_mode) && ::stat(d.dir.c_str(), &dir) == 0 && (dir.st_mode & S_ISVTX) &&
        ::geteuid() != 0 && d.existing.st_uid != ::geteuid() && dir.st_uid != ::geteuid())
        throw Error("cannot write '" + path + "': it belongs to another user in the sticky directory '" +
                    d.dir.string() + "', where only its owner may replace it (outputs are written beside their "
                    "target and renamed over it)");
    return d;
}

}  // namespace

void check_writable(const std::string& path) {
    const Destination d = destination_of(path);
    if (d.exists && !S_ISREG(d.existing.st_mode)) return;  // written into, not replaced: opened then
    if (::faccessat(AT_FDCWD, d.dir.c_str(), W_OK | X_OK, AT_EACCESS) != 0)
        throw Error("cannot write '" + path + "': cannot create a file in '" + d.dir.string() + "' (" +
                    std::strerror(errno) + ")" +
                    (d.exists ? "; outputs are written beside their target and renamed over it" : ""));
}

void write_file_atomically(const std::string& path, const std::function<void(std::FILE*)>& write) {
    const Destination d = destination_of(path);
    const std::string& destination = d.path;
    const std::filesystem::path target(destination);
    const std::filesystem::path& dir = d.dir;
    const struct stat& existing = d.existing;
    const bool exists = d.exists;
    if (exists && !S_ISREG(existing.st_mode)) return write_into_special_file(path, destination, write);

    std::string temp;
    // Listed while it exists; a signal after the rename unlinks a name that is gone.
    ListedTemporary listed;
    // Created no more open than the file it replaces: made 0666 and narrowed by fchmod below, a
    // private output's temporary was readable by anyone for a moment, long enough to open it
    // and read the new contents through that descriptor.
    const int fd = create_temp(dir, target.filename().string(), temp, listed, exists ? (existing.st_mode & 0777) : 0666);
    if (fd < 0) {
        const std::string reason = std::strerror(errno);
        if (exists)  // the file itself is writable: say what was refused
            throw Error("cannot write '" + path + "': cannot create a temporary file in '" + dir.string() + "' (" +
                        reason + "); outputs are written beside their target and renamed over it");
        throw Error("cannot write '" + path + "': " + reason);
    }
    // A file replaced keeps its owner where this process may give it (root may) and its
    // permissions (as `>` would), not the umask's: a private output stays private. Not its
    // set-id bits.
    if (exists) {
        if (existing.st_uid != ::geteuid() || existing.st_gid != ::getegid())
            (void)::fchown(fd, existing.st_uid, existing.st_gid);
        (void)::fchmod(fd, existing.st_mode & 0777);
    }
    std::FILE* file = fdopen(fd, "wb");
    if (!file) {
        ::close(fd);
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    }
    try {
        write(file);
        // ferror: a failed write inside fprintf is remembered there, and a later fflush of an
        // empty buffer would not report it.
        if (std::fflush(file) != 0 || std::ferror(file) || ::fsync(fileno(file)) != 0)
            throw Error(std::string("write failed: ") + std::strerror(errno));
    } catch (const std::exception& e) {
        std::fclose(file);
        ::unlink(temp.c_str());
        throw_write_failure(path, e);
    }
    if (std::fclose(file) != 0) {
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(errno));
    }
    if (std::rename(temp.c_str(), destination.c_str()) != 0) {
        const int err = errno;
        ::unlink(temp.c_str());
        throw Error("cannot write '" + path + "': " + std::strerror(err));
    }
    // The rename is in the directory: synced too, so a power cut after we return leaves the new
    // file under its name, not the old one. Best effort: the file is whole either way, and some
    // file systems refuse fsync on a directory.
    const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd >= 0) {
        (void)::fsync(dir_fd);
        ::close(dir_fd);
    }
}

void write_to_stream(std::FILE* file, const std::string& name, const std::function<void(std::FILE*)>& write) {
    try {
        write(file);
        if (std::fflush(file) != 0 || std::ferror(file)) throw Error(std::string("write failed: ") + std::strerror(errno));
    } catch (const std::exception& e) {
        throw_write_failure(name, e);
    }
}

namespace {

// Where a memory stream's writes go. stdio is C, so nothing may be thrown through it: a
// failed append fails the write, and running out of memory is remembered for the caller.
struct MemorySink {
    std::vector<unsigned char> bytes;
    bool out_of_memory = false;
};

ssize_t append_to_sink(void* cookie, const char* data, std::size_t size) {
    auto* sink = static_cast<MemorySink*>(cookie);
    try {
        sink->bytes.insert(sink->bytes.end(), data, data + size);
        return static_cast<ssize_t>(size);
    } catch (const std::bad_alloc&) {
        sink->out_of_memory = true;
        errno = ENOMEM;
    } catch (...) {  // length_error: more than a vector holds
        errno = EFBIG;
    }
    return 0;  // fopencookie's "nothing written, an error"
}

}  // namespace

std::vector<unsigned char> write_to_memory(const std::string& name, const std::function<void(std::FILE*)>& write,
                                           std::size_t expected_bytes) {
    const auto out_of_memory = [&] { return OutOfMemoryError("cannot write '" + name + "': out of memory"); };
    MemorySink sink;
    try {
        sink.bytes.reserve(expected_bytes);
    } catch (const std::bad_alloc&) {
        throw out_of_memory();
    }
    cookie_io_functions_t io{};
    io.write = append_to_sink;
    std::FILE* file = ::fopencookie(&sink, "w", io);
    if (!file) throw out_of_memory();  // its only failure
    try {
        write_to_stream(file, name, write);
    } catch (const Error&) {
        std::fclose(file);
        if (sink.out_of_memory) throw out_of_memory();
        throw;
    }
    if (std::fclose(file) != 0) throw Error("cannot write '" + name + "': " + std::strerror(errno));
    // Grown by doubling (a size not known before): up to half of it spare, given back.
    if (sink.bytes.capacity() - sink.bytes.size() > sink.bytes.size() / 8) {
        try {
            sink.bytes.shrink_to_fit();
        } catch (const std::bad_alloc&) {  // keeps the spare room: still the right bytes
        }
    }
    return std::move(sink.bytes);
}

}  // namespace voxmesh::detail

namespace voxmesh {

void remove_partial_outputs() noexcept {
    for (detail::InFlight& slot : detail::g_in_flight)
        if (slot.ready.load(std::memory_order_acquire)) ::unlink(slot.path);
}

}  // namespace voxmesh
