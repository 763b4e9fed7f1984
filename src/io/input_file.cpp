#include "input_file.hpp"

#include <voxmesh/voxmesh.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace voxmesh::io {

void fail(const std::string& path, const std::string& what) { throw Error("'" + path + "': " + what); }

InputFile::InputFile(const std::string& path) : path_(path) {
    // O_NONBLOCK so that a FIFO given by mistake cannot hang the open.
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd_ < 0) {
        const int err = errno;
        if (err == ENOENT) fail(path, "file does not exist");
        fail(path, std::string("cannot open: ") + std::strerror(err));
    }
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
        const int err = errno;
        ::close(fd_);
        fail(path, std::string("cannot stat: ") + std::strerror(err));
    }
    if (!S_ISREG(st.st_mode)) {
        ::close(fd_);
        fail(path, S_ISDIR(st.st_mode) ? "is a directory, not a file" : "is not a regular file");
    }
    size_ = static_cast<std::size_t>(st.st_size);
}

InputFile::InputFile(const std::string& name, const void* data, std::size_t size)
    : path_(name), memory_(static_cast<const unsigned char*>(data)), size_(size) {
    static const unsigned char kNothing = 0;
    if (memory_ == nullptr) {
        if (size != 0) fail(name, "no bytes given (a null pointer with a size of " + std::to_string(size) + ")");
        memory_ = &kNothing;  // empty, but still in memory
    }
}

InputFile::InputFile(const std::string& name, std::shared_ptr<unsigned char> owned, std::size_t size)
    : InputFile(name, owned.get(), size) {
    owned_ = std::move(owned);
}

InputFile::~InputFile() {
    if (fd_ >= 0) ::close(fd_);
}

std::string InputFile::read(std::size_t offset, std::size_t max_bytes) const {
    if (offset >= size_) return {};
    std::string out(std::min(max_bytes, size_ - offset), '\0');
    read_exact(offset, out.data(), out.size());
    return out;
}

void InputFile::read_exact(std::size_t offset, void* out, std::size_t bytes) const {
    if (in_memory()) {
        if (offset > size_ || bytes > size_ - offset) fail(path_, "file ended early");
        if (bytes > 0) std::memcpy(out, memory_ + offset, bytes);
        return;
    }
    auto* dst = static_cast<char*>(out);
    while (bytes > 0) {
        const ssize_t got = ::pread(fd_, dst, std::min<std::size_t>(bytes, 1 << 30), static_cast<off_t>(offset));
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) fail(path_, std::string("read failed: ") + std::strerror(errno));
        if (got == 0) fail(path_, "file ended early (was it truncated while being read?)");
        dst += got;
        offset += static_cast<std::size_t>(got);
        bytes -= static_cast<std::size_t>(got);
    }
}

namespace {
std::atomic<bool> g_refuse_mmap{false};  // refuse_mmap_for_testing
}  // namespace

void refuse_mmap_for_testing(bool refuse) { g_refuse_mmap.store(refuse); }

std::shared_ptr<unsigned char> InputFile::map() const {
    if (size_ == 0) fail(path_, "file is empty");
    if (owned_) return owned_;
    if (in_memory()) return copy();
    // NORESERVE: the private mapping is only copied where someone writes to it.
    void* base = g_refuse_mmap.load() ? MAP_FAILED
                                      : ::mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_NORESERVE, fd_, 0);
    if (base != MAP_FAILED) {
        const std::size_t length = size_;
        return std::shared_ptr<unsigned char>(static_cast<unsigned char*>(base),
                                              [length](unsigned char* p) { ::munmap(p, length); });
    }
    // A filesystem without mmap (some FUSE and network mounts) or the process's map-count
    // limit: read the file into memory instead, which is what a copy would cost anyway.
    return copy();
}

std::shared_ptr<unsigned char> InputFile::copy() const {
    check_memory(path_, size_);
    return out_of_memory_reading(path_, "file", [&] {
        std::shared_ptr<unsigned char> copy(new unsigned char[size_], std::default_delete<unsigned char[]>());
        read_exact(0, copy.get(), size_);
        return copy;
    });
}

std::shared_ptr<const unsigned char> InputFile::view() const {
    if (size_ == 0) fail(path_, "file is empty");
    if (in_memory()) return {std::shared_ptr<const unsigned char>(), memory_};  // aliasing: owns nothing
    return map();
}

MappedFile map_whole_file(const InputFile& file) {
    MappedFile mapped;
    mapped.mapping = file.view();  // a mapping outlives the descriptor
    mapped.text = std::string_view(reinterpret_cast<const char*>(mapped.mapping.get()), file.size());
    return mapped;
}

std::size_t physical_memory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages > 0 && page > 0) return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page);
    return static_cast<std::size_t>(-1);
}

std::size_t available_memory() {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    std::size_t kb = 0;
    std::string unit;
    while (meminfo >> key >> kb >> unit) {
        if (key == "MemAvailable:") return kb * 1024;
    }
    return physical_memory();
}

void check_memory(const std::string& path, std::size_t bytes) {
    const std::size_t available = available_memory();
    if (bytes > available)
        fail(path, "reading it needs " + std::to_string(bytes) + " bytes of memory but only " +
                       std::to_string(available) + " bytes are available");
}

bool ends_with_nocase(const std::string& path, const std::string& suffix) {
    if (path.size() < suffix.size()) return false;
    return std::equal(suffix.begin(), suffix.end(), path.end() - static_cast<std::ptrdiff_t>(suffix.size()),
                      [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) ==
                                                  std::tolower(static_cast<unsigned char>(b)); });
}

std::string detached_data_path(const InputFile& header, const std::string& name) {
    if (header.in_memory())
        fail(header.path(), "names a separate data file '" + name +
                                "'; a header read from memory must hold its samples itself");
    const std::filesystem::path p(name);
    if (p.is_absolute()) return name;
    return (std::filesystem::path(header.path()).parent_path() / p).string();
}

}  // namespace voxmesh::io
