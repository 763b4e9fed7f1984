// Small strict parsers shared by the text headers (NRRD, MetaImage) and the text mesh formats:
// a number must be the whole token, or it is an error naming the file and the field.
#pragma once

#include "input_file.hpp"

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace voxmesh::io {

// The most header bytes the NRRD reader reads looking for the blank line that ends it; the
// writer refuses a header (its key/value lines) longer than that.
constexpr std::size_t kMaxNrrdHeader = std::size_t{1} << 20;

std::string_view trim(std::string_view text);
// `token` fit for an error message: at most 40 characters, control and non-ASCII bytes as '?'.
std::string shown(std::string_view token);
// The shortest text that reads back as the same double (std::to_string prints 1e300 with 300
// digits, and 1e-300 as 0.000000).
std::string shortest_text(double value);
std::string lower(std::string_view text);
std::vector<std::string_view> split_words(std::string_view text);

// The next line of `text` from `pos` (without "\n" or "\r\n"); false at the end.
bool next_line(std::string_view text, std::size_t& pos, std::string_view& line);
// The same for the text mesh formats, where a lone "\r" (classic Mac OS exporters) ends a
// line too.
bool next_text_line(std::string_view text, std::size_t& pos, std::string_view& line);
// Whether text[i] ends a line as next_text_line counts them ("\r\n" once, at its '\n').
inline bool ends_text_line(std::string_view text, std::size_t i) {
    return text[i] == '\n' || (text[i] == '\r' && (i + 1 == text.size() || text[i + 1] != '\n'));
}
// 3 when `text` starts with a UTF-8 byte order mark (Windows tools write one before the
// text), else 0.
std::size_t bom_size(std::string_view text);

std::size_t parse_size(const std::string& path, std::string_view field, std::string_view token);
long long parse_integer(const std::string& path, std::string_view field, std::string_view token);
double parse_double(const std::string& path, std::string_view field, std::string_view token);
// A decimal number word of a text mesh format (ASCII STL, ASCII PLY, OBJ) as float: the whole
// word, an optional '+'; a value too small for a float reads as a signed zero, one beyond its
// range is refused. Returns nullptr, or what is wrong with the word ("is not a number", ...);
// `word` loses its '+', as it is then shown.
const char* float_word(std::string_view& word, float& value);
// The same for a double (ASCII legacy VTK samples): "1e-400" is a signed zero, "1e400" refused.
const char* double_word(std::string_view& word, double& value);
// float_word, refusing with Error("'path': " + where() + "'word' is ..."). `where` (the line,
// the record) is called only for that, not for every number read.
template <class Where>
float parse_float_word(const std::string& path, const Where& where, std::string_view word) {
    float value = 0;
    if (const char* problem = float_word(word, value)) {
        std::string what = where();  // built with append: gcc 12's false -Wrestrict on + chains
        what.append("'").append(shown(word)).append("' ").append(problem);
        fail(path, what);
    }
    return value;
}
// Whitespace-separated numbers; the count must be `expected` (when non-zero).
std::vector<double> parse_doubles(const std::string& path, std::string_view field, std::string_view value,
                                  std::size_t expected);
std::vector<std::size_t> parse_sizes(const std::string& path, std::string_view field, std::string_view value);

}  // namespace voxmesh::io
