// Shared by the voxmesh tool and voxmesh-bench: options that take a value refuse an empty one.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace voxmesh::cli {

// CLI11 reads '' as 0 for a number, so an unset shell variable (--iso "$ISO") would run with
// 0 without a word. Applies to the app's options and to every subcommand's, recursively; call
// it once every option is declared.
inline void refuse_empty_values(CLI::App& app) {
    const CLI::Validator non_empty([](std::string& text) { return text.empty() ? std::string("empty value") : std::string(); },
                                   "", "NONEMPTY");
    for (CLI::Option* option : app.get_options())
        if (option->get_expected_min() > 0 && option->get_type_size_max() > 0) option->check(non_empty);
    for (CLI::App* sub : app.get_subcommands({})) refuse_empty_values(*sub);
}

}  // namespace voxmesh::cli
