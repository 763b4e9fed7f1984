// Shared by the voxmesh tool and voxmesh-bench: checks of option values.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>
#include <system_error>

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

// A whole number from lo to hi, in decimal ("010" is 10, "0x10" is refused), checked on the
// text, as a negative number given for an unsigned type wraps around (CLI::Range said "Value
// abc not in range 2 to 4096" of text that is no number, and of 100.5, which is in the range).
// Give it with Option::transform, not check: check() marks a validator non-modifying, so the
// decimal text it hands on would not reach CLI11's conversion, which reads "010" as octal 8.
// An empty value is left to refuse_empty_values' message.
inline CLI::Validator whole_number_in(long long lo, long long hi) {
    return CLI::Validator(
        [lo, hi](std::string& text) {
            if (text.empty()) return std::string();
            long long value = 0;
            const char* end = text.data() + text.size();
            const auto [ptr, ec] = std::from_chars(text.data(), end, value);
            if (ptr != end || (ec != std::errc() && ec != std::errc::result_out_of_range))
                return "'" + text + "' is not a whole number";
            if (ec != std::errc() || value < lo || value > hi)
                return text + " is out of range (" + std::to_string(lo) + ".." + std::to_string(hi) + ")";
            // Handed on in plain decimal: CLI11 converts integers with base 0, so "010" would
            // become 8 (octal) after being checked here as 10.
            text = std::to_string(value);
            return std::string();
        },
        "INT in [" + std::to_string(lo) + " - " + std::to_string(hi) + "]");
}

// A real number in decimal ("1.5", "-2e3", "+4"; "inf" and "nan" are left to the option's own
// finiteness check, which names the option). CLI11 converts with strtold, which also takes hex
// ("--iso 0x10" ran at 16, a value nobody wrote) and leading blanks, and turns an overflowing
// exponent into inf without a word. Give it with Option::transform: the value is handed on in
// round-trip decimal so CLI11's conversion reads the number checked here.
inline CLI::Validator decimal_number() {
    return CLI::Validator(
        [](std::string& text) {
            if (text.empty()) return std::string();
            const char* begin = text.data();
            const char* end = text.data() + text.size();
            if (*begin == '+' && end - begin > 1 && begin[1] != '-' && begin[1] != '+') ++begin;  // from_chars takes no '+'
            double value = 0;
            const auto [ptr, ec] = std::from_chars(begin, end, value, std::chars_format::general);
            if (ptr != end || (ec != std::errc() && ec != std::errc::result_out_of_range))
                return "'" + text + "' is not a decimal number";
            if (ec == std::errc::result_out_of_range) {  // from_chars says so of 1e-400 as of 1e400
                value = std::strtod(std::string(begin, end).c_str(), nullptr);  // 0 or a denormal, or inf
                if (std::isinf(value)) return text + " is out of range of a double";
            }
            // CLI11 reads the text with strtold and rounds that to double: rounding twice, it
            // turns about 1 in 10^4 shortest forms into the next double (6.449645412599608e-280,
            // the shortest form of 6.4496454125996075e-280, came back as ...6085e-280). 17
            // significant digits lie far enough from a rounding midpoint to survive it.
            char buffer[64];
            auto written = std::to_chars(buffer, buffer + sizeof buffer - 1, value);
            *written.ptr = '\0';
            if (std::isfinite(value) && static_cast<double>(std::strtold(buffer, nullptr)) != value) {
                written = std::to_chars(buffer, buffer + sizeof buffer - 1, value, std::chars_format::scientific, 16);
                *written.ptr = '\0';
            }
            text.assign(buffer, written.ptr);
            return std::string();
        },
        "NUMBER");
}

}  // namespace voxmesh::cli
