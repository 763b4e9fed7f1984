// An input named "-": standard input copied to a temporary file (in TMPDIR), named with the
// format its first bytes show, so that the readers (which map files and seek in them) read it
// as any file. Messages call it "standard input", not the temporary file. The copy is listed
// with the outputs' temporaries, so remove_partial_outputs() in a signal handler removes it.
#pragma once

#include "common.hpp"

#include "core/atomic_file.hpp"
#include "core/out_of_memory.hpp"

#include <string>

namespace voxmesh::cli {

inline constexpr const char* kStdinName = "standard input";

// How messages name an input argument.
inline std::string input_name(const std::string& arg) { return arg == "-" ? kStdinName : arg; }

// What an input may be: the format is told from the content, among these (Raw: headerless
// samples, described by flags, and Text, a stroke script: taken as they are).
enum class InputKind { Volume, Model, VolumeOrModel, Raw, Text };

// The extension of the format the first bytes (`head`) of a file of `size` bytes show, or ""
// when none of `kind`: ".nrrd", ".vtk", ".npy", ".nii.gz", ".nii", ".mha" (volumes), ".ply", ".stl", ".obj"
// (models).
std::string sniff_format(const std::string& head, std::size_t size, InputKind kind);

class InputPath {
public:
    // `arg` as given, checked to be a readable non-empty file (check_input_file); "-" reads all
    // of standard input now (BadInput when it is a terminal, empty, not of `kind`, or cannot be
    // spooled).
    InputPath(const std::string& arg, InputKind kind);
    ~InputPath();
    InputPath(const InputPath&) = delete;
    InputPath& operator=(const InputPath&) = delete;

    const std::string& path() const { return path_; }        // for the readers
    const std::string& display() const { return display_; }  // for messages
    // `text` with the spooled file's path (if any) named as standard input.
    std::string shown(std::string text) const;

    // about_file for this input, naming display() (not the temporary copy).
    template <class F>
    auto read(F&& f) const -> decltype(f()) {
        return about_file(display_, [&] {
            try {
                return f();
            } catch (const voxmesh::Error& e) {
                detail::rethrow_with_message(e, shown(e.what()));
            }
        });
    }

private:
    void remove_spool() noexcept;

    bool spooled_ = false;  // path_ is the copy of standard input, removed with this object
    std::string path_, display_;
    // The copy under its first name and under its format's, listed for the signal handler's
    // remove_partial_outputs() while they exist.
    detail::ListedTemporary copy_listed_, named_listed_;
};

// The model `arg` names (a .stl, .ply or .obj file, or "-"), read for `command`; BadInput
// naming it when it cannot be.
Mesh load_model(const std::string& arg, const std::string& command);

}  // namespace voxmesh::cli
