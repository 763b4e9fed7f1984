// voxmesh::Error promises that every failure throws it: std::bad_alloc from deep inside a call
// (a vector growing, a mapping refused) becomes one at the public entry points.
#pragma once

#include <voxmesh/voxmesh.hpp>

#include <new>
#include <string>

namespace voxmesh::detail {

// Returns f(); std::bad_alloc out of it becomes OutOfMemoryError(message()), which says what
// ran out. The message is made only then: some callers run every frame (Sculpt::update).
template <class Message, class F>
auto out_of_memory_as_error(const Message& message, F&& f) {
    try {
        return f();
    } catch (const std::bad_alloc&) {
        throw OutOfMemoryError(message());
    }
}

// Throws an Error of e's kind (an OutOfMemoryError stays one) with `message`: for the places
// that put a file's name or more context in front of an Error from below.
[[noreturn]] inline void rethrow_with_message(const Error& e, const std::string& message) {
    if (dynamic_cast<const OutOfMemoryError*>(&e)) throw OutOfMemoryError(message);
    throw Error(message);
}

// "out of memory for a mesh of V vertices and T triangles"
inline std::string out_of_memory_for(const Mesh& mesh) {
    return "out of memory for a mesh of " + std::to_string(mesh.vertex_count()) + " vertices and " +
           std::to_string(mesh.triangle_count()) + " triangles";
}

}  // namespace voxmesh::detail
