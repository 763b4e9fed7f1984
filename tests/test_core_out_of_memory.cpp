// Out of memory is a voxmesh::OutOfMemoryError (an Error), never a std::bad_alloc, from extract, analyze_topology,
// keep_largest_components, the volume and mesh readers, voxelize, make_field, the
// stroke-script parser, and a Sculpt's construction, update and mesh. Each call runs in a
// forked child whose private writable memory is capped (RLIMIT_DATA) a little above what it
// uses already, so that its large allocations fail; the same call with room to spare must
// return, so the cap is what made it fail.
#include "support/child_process.hpp"
#include "support/mesh_checks.hpp"
#include "support/sanitizers.hpp"

#include "core/atomic_file.hpp"

#include <voxmesh/fields.hpp>
#include <voxmesh/io.hpp>
#include <voxmesh/sculpt.hpp>
#include <voxmesh/voxelize.hpp>
#include <voxmesh/voxmesh.hpp>

#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

// The sanitizers' allocators die rather than throw.
constexpr bool kCapWorks = !vmtest::kAddressSanitizer && !vmtest::kThreadSanitizer;

// VmData: the process's private writable memory, what RLIMIT_DATA caps. (RLIMIT_AS would
// not do: glibc's per-thread malloc arenas reserve 64 MB of address space each, and a failed
// allocation is retried in another arena, which grows into its reservation uncounted.)
std::size_t data_bytes() { return vmtest::proc_status_number("VmData:") * 1024; }

// In a capped child: back to the hard limit, to retry what ran out.
void lift_cap() {
    rlimit cap{};
    getrlimit(RLIMIT_DATA, &cap);
    cap.rlim_cur = cap.rlim_max;
    setrlimit(RLIMIT_DATA, &cap);
}

// Bytes of thread arenas' heaps that shrank but stay writable, so charged to VmData already:
// glibc gives them back with MADV_DONTNEED, not mprotect, and mallinfo2 does not count them
// free. A capped allocation that fails in the calling thread's arena is retried in another,
// which grows into them past the cap (seen running "[io]" in one process: reading a volume
// with no room at all returned). malloc_info's totals: "mprotect" minus "total" address space.
std::size_t shrunk_heap_bytes() {
    char* text = nullptr;
    std::size_t length = 0;
    std::FILE* stream = open_memstream(&text, &length);
    if (!stream) return 0;
    malloc_info(0, stream);
    std::fclose(stream);
    const std::string info(text, length);
    std::free(text);
    // The last of each is the sum over every arena (the main one's two are equal).
    const auto last_size = [&](const std::string& type) -> std::size_t {
        const std::string key = "<aspace type=\"" + type + "\" size=\"";
        const std::size_t at = info.rfind(key);
        return at == std::string::npos ? 0 : std::strtoull(info.c_str() + at + key.size(), nullptr, 10);
    };
    const std::size_t total = last_size("total"), writable = last_size("mprotect");
    return writable > total ? writable - total : 0;
}

// In a child about to be capped: takes up the memory malloc holds freed (kept; the child exits),
// so that what the call allocates must be new memory, which the cap can refuse. Freed memory is
// handed out past any cap: the set-up of an earlier section left 2.7-3.5 MB free, under
// cap_can_be_tight's 4 MB, and the OBJ reader's arrays fitted in it in about half the runs.
void take_up_freed_memory() {
    constexpr std::size_t kLeft = std::size_t{64} << 10;
    std::size_t size = mallinfo2().fordblks / 2;
    for (int step = 0; step < 10000 && size >= 64 && mallinfo2().fordblks > kLeft; ++step) {
        const std::size_t before = mallinfo2().fordblks;
        if (!std::malloc(size)) break;
        if (mallinfo2().fordblks + size / 2 > before) size /= 2;  // not served from freed memory
    }
    // Then the other arenas' shrunk heaps. After fork every arena but the caller's is free, and
    // a new thread takes a free one: each thread takes up its arena's until VmData grows, and
    // stays until the last is done so that the next one takes another arena.
    std::vector<std::thread> holders;
    std::deque<std::promise<void>> took_up;  // kept until the joins: set_value may still be returning
    std::promise<void> release;
    const std::shared_future<void> released = release.get_future().share();
    for (int t = 0; t < 16 && shrunk_heap_bytes() > kLeft; ++t) {
        std::promise<void>& done = took_up.emplace_back();
        std::future<void> done_future = done.get_future();
        holders.emplace_back([&done, released] {
            const std::size_t charged = data_bytes();
            for (int step = 0; step < 1024 && data_bytes() == charged; ++step)  // 64 MB at most: a heap
                if (!std::malloc(std::size_t{64} << 10)) break;
            done.set_value();
            released.wait();
        });
        done_future.wait();
    }
    release.set_value();
    for (std::thread& holder : holders) holder.join();
}

// What `call` did in a child process capped at its data bytes + `headroom`: "returned",
// "OutOfMemoryError: <message>", "Error: <message>" (another Error), "bad_alloc" or "other
// exception" (or why the child said nothing).
std::string outcome_when_capped(std::size_t headroom, const std::function<void()>& call) {
    return vmtest::output_of_child([&] {
        take_up_freed_memory();
        rlimit cap{};
        getrlimit(RLIMIT_DATA, &cap);
        cap.rlim_cur = data_bytes() + headroom;  // the soft limit: lift_cap() can raise it again
        if (setrlimit(RLIMIT_DATA, &cap) != 0) return std::string("setrlimit failed");
        // The cap is lifted before the outcome is put into words, which needs memory.
        try {
            call();
            lift_cap();
            return std::string("returned");
        } catch (const voxmesh::OutOfMemoryError& e) {
            lift_cap();
            return "OutOfMemoryError: " + std::string(e.what());
        } catch (const voxmesh::Error& e) {
            lift_cap();
            return "Error: " + std::string(e.what());
        } catch (const std::bad_alloc&) {
            lift_cap();
            return std::string("bad_alloc");
        } catch (...) {
            lift_cap();
            return std::string("other exception");
        }
    });
}

// Whether a cap just above the memory in use makes large allocations fail here; says why not
// (WARN) where it cannot:
//  * under a sanitizer, whose allocator reports running out and dies, throwing nothing;
//  * in a process whose malloc holds more than `max_free` bytes already freed (by earlier tests
//    run in the same process): an allocation served from them needs no new memory, and no cap
//    stops it. ctest runs each test case in a process of its own, where the set-up of these
//    tests leaves 0.3 to 3 MB.
bool cap_can_be_tight(std::size_t max_free = std::size_t{1} << 20) {
    if (!kCapWorks) {
        WARN("skipped under a sanitizer: its allocator reports running out and dies, it throws nothing");
        return false;
    }
    const std::size_t free_bytes = mallinfo2().fordblks;
    if (free_bytes > max_free) {
        WARN("skipped: malloc holds " << free_bytes << " free bytes from earlier tests in this process, which no "
             "cap can hold back; run this test case alone (as ctest does)");
        return false;
    }
    return true;
}

bool starts_with(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

constexpr std::size_t kTight = std::size_t{2} << 20, kRoomy = std::size_t{2} << 30;

// `call` returns with room to spare, and with `tight` bytes of room throws an OutOfMemoryError
// starting `expected`.
void check_out_of_memory_is_error(const std::function<void()>& call, const std::string& expected,
                                  std::size_t tight = kTight) {
    CHECK(outcome_when_capped(kRoomy, call) == "returned");
    const std::string outcome = outcome_when_capped(tight, call);
    INFO(outcome);
    CHECK(starts_with(outcome, "OutOfMemoryError: " + expected));
}

}  // namespace

TEST_CASE("out of memory is an Error from extract, analyze_topology and keep_largest_components", "[core][memory]") {
    // A dense surface: the mesh (about 20 MB) and the engine's scratch are far past 2 MB.
    const voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Gyroid, 128);
    const voxmesh::Options options = vmtest::cpu_options(field.iso, 1);  // no worker threads in the child
    const voxmesh::Mesh mesh = voxmesh::extract(field.volume.view(), options);
    REQUIRE(mesh.triangle_count() > 500000);
    if (!cap_can_be_tight()) return;
    const std::string mesh_size = "out of memory for a mesh of " + std::to_string(mesh.vertex_count()) +
                                  " vertices and " + std::to_string(mesh.triangle_count()) + " triangles";

    SECTION("extract") {
        check_out_of_memory_is_error([&] { (void)voxmesh::extract(field.volume.view(), options); },
                                     "out of memory meshing a 128x128x128 volume");
    }
    SECTION("analyze_topology") {
        check_out_of_memory_is_error([&] { (void)voxmesh::analyze_topology(mesh); }, "analyze_topology: " + mesh_size);
    }
    SECTION("keep_largest_components") {
        check_out_of_memory_is_error([&] { (void)voxmesh::keep_largest_components(mesh, 2); },
                                     "keep_largest_components: " + mesh_size);
    }
}

TEST_CASE("out of memory is an Error from the mesh readers and voxelize", "[io][memory]") {
    // A closed surface with about 200 000 triangles: 10 MB as STL, more as arrays.
    const voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 160);
    const voxmesh::Mesh mesh = voxmesh::extract(field.volume.view(), vmtest::cpu_options(field.iso, 1));
    REQUIRE(mesh.triangle_count() > 150000);
    if (!cap_can_be_tight(std::size_t{4} << 20)) return;  // the set-up leaves about 3 MB
    vmtest::TempDir dir;
    for (const char* name : {"sphere.stl", "sphere.ply", "sphere.obj"}) {
        DYNAMIC_SECTION(name) {
            const std::string path = dir.file(name);
            voxmesh::write_mesh(path, mesh);
            // Room for the file's mapping (private and writable, so it counts), not the arrays.
            check_out_of_memory_is_error([&] { (void)voxmesh::read_mesh(path); },
                                         "'" + path + "': out of memory reading the mesh",
                                         std::filesystem::file_size(path) + kTight);
        }
    }
    SECTION("voxelize") {
        voxmesh::VoxelizeOptions vo;
        vo.resolution = 64;  // a small grid: the welding of the mesh's corners runs out first
        vo.threads = 1;
        check_out_of_memory_is_error([&] { (void)voxmesh::voxelize(mesh, vo); },
                                     "voxelize: out of memory for a mesh of " + std::to_string(mesh.vertex_count()));
    }
}

TEST_CASE("out of memory is an Error from reading and writing meshes in memory", "[io][memory]") {
    // About 400 000 triangles: each format's arrays and bytes are well past the 4 MB that the
    // set-up may leave free plus the cap's 2 MB of room.
    const voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 256);
    const voxmesh::Mesh mesh = voxmesh::extract(field.volume.view(), vmtest::cpu_options(field.iso, 1));
    REQUIRE(mesh.triangle_count() > 350000);
    // All read before the checks, in one allocation each: memory freed between them would be
    // malloc's to hand out again, past any cap.
    const char* const names[] = {"sphere.stl", "sphere.ply", "sphere.obj"};
    vmtest::TempDir dir;
    std::vector<std::vector<unsigned char>> files;
    for (const char* name : names) {
        const std::string path = dir.file(name);
        voxmesh::write_mesh(path, mesh);
        std::ifstream in(path, std::ios::binary);
        std::vector<unsigned char>& bytes = files.emplace_back(std::filesystem::file_size(path));
        in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    if (!cap_can_be_tight(std::size_t{4} << 20)) return;
    for (std::size_t f = 0; f < files.size(); ++f) {
        const std::string name = names[f];
        INFO(name);
        check_out_of_memory_is_error(
            [&] { (void)voxmesh::read_mesh_from_memory(files[f].data(), files[f].size(), name); },
            "'" + name + "': out of memory reading the mesh");
        check_out_of_memory_is_error([&] { (void)voxmesh::write_mesh_to_memory(mesh, name); },
                                     "cannot write '" + name + "': out of memory");
    }
}

TEST_CASE("a write that runs out of memory says so and leaves nothing", "[core][memory]") {
    vmtest::TempDir dir;
    const std::string path = dir.file("mesh.stl");
    try {
        voxmesh::detail::write_file_atomically(path, [](std::FILE*) { throw std::bad_alloc(); });
        FAIL("no error");
    } catch (const voxmesh::OutOfMemoryError& e) {
        CHECK(std::string(e.what()) == "cannot write '" + path + "': out of memory");
    }
    CHECK(dir.entries().empty());
}

TEST_CASE("out of memory is an Error from Sculpt::update, which can be retried, and Sculpt::mesh", "[sculpt][memory]") {
    voxmesh::SculptOptions options;
    options.threads = 1;  // no worker threads in the child
    options.backend = voxmesh::Backend::Cpu;
    voxmesh::Sculpt sculpt = voxmesh::make_sculpt_sphere(256, options);  // every block dirty, none meshed
    REQUIRE(sculpt.dirty());
    if (!cap_can_be_tight()) return;

    SECTION("update") {
        const voxmesh::Mesh expected = voxmesh::extract(sculpt.view(), vmtest::cpu_options(0, 1));
        REQUIRE(expected.triangle_count() > 100000);
        // Runs out, stays dirty, and once there is memory again gives the whole mesh.
        check_out_of_memory_is_error(
            [&] {
                try {
                    sculpt.update();
                } catch (const voxmesh::Error&) {
                    lift_cap();
                    if (!sculpt.dirty()) throw voxmesh::Error("not dirty after a failed update");
                    sculpt.update();
                    const voxmesh::Mesh mesh = sculpt.mesh();
                    if (mesh.indices != expected.indices || mesh.positions != expected.positions)
                        throw voxmesh::Error("a different mesh after the retried update");
                    throw;
                }
            },
            "sculpt: out of memory re-meshing " + std::to_string(sculpt.block_count()) + " blocks");
    }
    SECTION("a retried update lists the blocks the failed one emptied") {
        // Blocks are re-meshed in index order on one worker: the z < 64 blocks (some on the
        // sphere) are emptied first, with no allocation, then the z >= 224 blocks, filled with a
        // checkerboard, need far more than the cap. A renderer redrawing `changed` must hear of
        // the emptied blocks from the retry, though their stores were emptied by the failure.
        sculpt.update();
        std::vector<std::size_t> emptied;
        for (std::size_t b = 0; b < sculpt.block_count(); ++b)
            if (sculpt.block(b).coord[2] < 2 && !sculpt.block(b).indices.empty()) emptied.push_back(b);
        REQUIRE_FALSE(emptied.empty());
        check_out_of_memory_is_error(
            [&] {
                auto* samples = static_cast<float*>(sculpt.data());
                const std::size_t plane = 256 * 256;
                std::fill(samples, samples + 66 * plane, -100.0f);  // block z 1 reads samples up to z 65
                for (std::size_t i = 224 * plane; i < 256 * plane; ++i) samples[i] = (i + i / 256 + i / plane) % 2 ? 1.f : -1.f;
                sculpt.invalidate_all();
                try {
                    sculpt.update();
                } catch (const voxmesh::Error&) {
                    lift_cap();
                    const voxmesh::UpdateResult retried = sculpt.update();
                    for (std::size_t b : emptied) {
                        if (!sculpt.block(b).indices.empty()) throw voxmesh::Error("an emptied block has triangles");
                        if (!std::binary_search(retried.changed.begin(), retried.changed.end(), b))
                            throw voxmesh::Error("block " + std::to_string(b) + " was emptied and is not in changed");
                    }
                    throw;
                }
            },
            "sculpt: out of memory re-meshing " + std::to_string(sculpt.block_count()) + " blocks");
    }
    SECTION("mesh") {
        sculpt.update();
        check_out_of_memory_is_error([&] { (void)sculpt.mesh(); },
                                     "sculpt: out of memory welding the blocks' meshes into one");
    }
}

// Found by a review: update() cleared each block's dirty flag while it listed the changed blocks,
// and a list that ran out of memory half-way left flags cleared for blocks still in the dirty
// list; the next edit of one of them listed it twice (re-meshed twice, on two workers at once).
TEST_CASE("an update that runs out of memory listing the changed blocks leaves every block dirty once",
          "[sculpt][memory]") {
    voxmesh::SculptOptions options;
    options.threads = 1;
    options.backend = voxmesh::Backend::Cpu;
    options.iso = 128;
    options.block_size = 2;  // 50^3 blocks, nearly all crossed by the surface
    voxmesh::Sculpt sculpt = voxmesh::Sculpt::from_function(
        {101, 101, 101}, voxmesh::ScalarType::U8,
        [](double x, double y, double z) { return 128 + 100 * std::sin(1.7 * x) * std::sin(1.3 * y) * std::sin(1.1 * z); },
        options);
    sculpt.update();
    if (!cap_can_be_tight()) return;
    // Every block re-meshed as it was needs no new memory: only the list of changed blocks
    // (1 MB) grows, past the cap.
    check_out_of_memory_is_error(
        [&] {
            sculpt.invalidate_all();
            try {
                sculpt.update();
            } catch (const voxmesh::Error&) {
                lift_cap();
                sculpt.set_region({0, 0, 0}, {0, 0, 0}, 255 - static_cast<const std::uint8_t*>(sculpt.view().data)[0]);
                const voxmesh::UpdateResult retried = sculpt.update();
                if (retried.remeshed != sculpt.block_count())
                    throw voxmesh::Error("the retried update re-meshed " + std::to_string(retried.remeshed) + " of " +
                                         std::to_string(sculpt.block_count()) + " blocks");
                if (std::adjacent_find(retried.changed.begin(), retried.changed.end()) != retried.changed.end())
                    throw voxmesh::Error("a block listed twice as changed");
                throw;
            }
        },
        "sculpt: out of memory re-meshing 125000 blocks", std::size_t{256} << 10);
}

// Found by a review: the smooth brush's two plane buffers (16 bytes a sample of the x-y extent
// it smooths, 32 MB here for a 4 MB volume) let std::bad_alloc out of Sculpt::smooth.
TEST_CASE("out of memory is an Error from the smooth brush and changes nothing", "[sculpt][memory]") {
    voxmesh::SculptOptions options;
    options.threads = 1;
    options.backend = voxmesh::Backend::Cpu;
    options.iso = 100;
    voxmesh::Sculpt sculpt = voxmesh::Sculpt::from_function(
        {2048, 1024, 2}, voxmesh::ScalarType::U8, [](double x, double y, double) { return (x + y) / 16; }, options);
    sculpt.update();
    if (!cap_can_be_tight()) return;
    check_out_of_memory_is_error(
        [&] {
            try {
                sculpt.smooth({1024, 512, 0}, 1e6, 1);
            } catch (const voxmesh::Error&) {
                lift_cap();
                if (sculpt.dirty()) throw voxmesh::Error("dirty after a smooth that ran out of memory");
                throw;
            }
        },
        "sculpt: out of memory for the smooth brush's planes of 2097152 samples");
}

TEST_CASE("out of memory is an Error naming the file from the volume readers", "[io][memory]") {
    if (!cap_can_be_tight()) return;
    // Gzip NRRD and NIfTI: the header, the mapping, the inflated samples each need memory.
    // Wherever in the read it runs out, it is an Error naming the file.
    for (const char* name : {"headsq.nrrd", "mri_someones_anatomy.nii.gz"}) {
        const std::string path = std::string(VOXMESH_TEST_DATA) + "/" + name;
        INFO(path);
        bool ran_out = false, returned = false;
        for (std::size_t room = 0; room <= (std::size_t{4} << 20); room += std::size_t{256} << 10) {
            INFO("room " << room);
            const std::string outcome = outcome_when_capped(room, [&] { (void)voxmesh::read_volume(path); });
            INFO(outcome);
            // The files are sound: an Error here is the cap's doing.
            const bool error = starts_with(outcome, "OutOfMemoryError: '" + path + "': ");
            CHECK((outcome == "returned" || error));
            ran_out = ran_out || error;
            returned = returned || outcome == "returned";
        }
        CHECK(ran_out);
        CHECK(returned);
    }
}

TEST_CASE("out of memory is an Error from a Sculpt's construction, make_field and the stroke-script parser",
          "[sculpt][memory]") {
    if (!cap_can_be_tight()) return;
    SECTION("a Sculpt's block table") {
        // Blocks of 2 cells: 64^3 of them, some 25 MB of table, for a volume of 2 MB that fits.
        const voxmesh::FieldVolume field = voxmesh::make_field(voxmesh::Field::Sphere, 128, voxmesh::ScalarType::U8);
        voxmesh::SculptOptions options;
        options.threads = 1;
        options.backend = voxmesh::Backend::Cpu;
        options.iso = field.iso;
        options.block_size = 2;
        check_out_of_memory_is_error([&] { (void)voxmesh::Sculpt(field.volume.view(), options); },
                                     "sculpt: out of memory for a 128x128x128 volume in 262144 blocks",
                                     field.volume.byte_size() + 2 * kTight);
    }
    SECTION("make_field") {
        check_out_of_memory_is_error([] { (void)voxmesh::make_field(voxmesh::Field::Gyroid, 128); },
                                     "cannot allocate 8388608 bytes for a volume");
    }
    SECTION("parse_stroke_script") {
        std::string script;
        for (int i = 0; i < 300000; ++i) script += "add 1 2 3 4 5\n";  // some 20 MB of dabs
        std::istringstream in(script);
        check_out_of_memory_is_error([&] { (void)voxmesh::parse_stroke_script(in, "big.strokes"); },
                                     "'big.strokes': out of memory reading the stroke script");
    }
}
