#include "header_text.hpp"

#include "input_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace voxmesh::io {

namespace {
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }
}  // namespace

std::string shown(std::string_view token) {
    // Keep messages readable when the token is binary garbage or huge.
    std::string out;
    for (char c : token.substr(0, 40)) out += (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) ? '?' : c;
    if (token.size() > 40) out += "...";
    return out;
}

std::string shortest_text(double value) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, result.ptr);
}

std::string_view trim(std::string_view text) {
    while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
    while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
    return text;
}

std::string lower(std::string_view text) {
    std::string out(text);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return out;
}

std::vector<std::string_view> split_words(std::string_view text) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && is_space(text[i])) ++i;
        const std::size_t start = i;
        while (i < text.size() && !is_space(text[i])) ++i;
        if (i > start) words.push_back(text.substr(start, i - start));
    }
    return words;
}

bool next_line(std::string_view text, std::size_t& pos, std::string_view& line) {
    if (pos >= text.size()) return false;
    const std::size_t end = text.find('\n', pos);
    const std::size_t stop = end == std::string_view::npos ? text.size() : end;
    line = text.substr(pos, stop - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end == std::string_view::npos ? text.size() : end + 1;
    return true;
}

bool next_text_line(std::string_view text, std::size_t& pos, std::string_view& line) {
    if (pos >= text.size()) return false;
    std::size_t end = pos;  // a plain loop: find_first_of makes a call per character
    while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
    line = text.substr(pos, end - pos);
    pos = end == text.size() ? end : end + (text[end] == '\r' && end + 1 < text.size() && text[end + 1] == '\n' ? 2 : 1);
    return true;
}

std::size_t bom_size(std::string_view text) { return text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0; }

long long parse_integer(const std::string& path, std::string_view field, std::string_view token) {
    long long value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size() || token.empty())
        fail(path, "field '" + std::string(field) + "': '" + shown(token) + "' is not an integer");
    return value;
}

std::size_t parse_size(const std::string& path, std::string_view field, std::string_view token) {
    std::size_t value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec == std::errc::result_out_of_range)
        fail(path, "field '" + std::string(field) + "': '" + shown(token) + "' is too large");
    if (ec != std::errc() || end != token.data() + token.size() || token.empty())
        fail(path, "field '" + std::string(field) + "': '" + shown(token) + "' is not a non-negative integer");
    return value;
}

double parse_double(const std::string& path, std::string_view field, std::string_view token) {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);  // from_chars rejects '+'
    double value = 0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || end != token.data() + token.size() || token.empty())
        fail(path, "field '" + std::string(field) + "': '" + shown(token) + "' is not a number");
    return value;
}

namespace {

// The power of ten of the leading significant digit of a decimal that from_chars accepted
// ("1e39" -> 39, "-0.05e-48" -> -50). For a float out of range it tells overflow (>= 0)
// from underflow (< 0) exactly, even where a double would be out of range too.
long long decimal_magnitude(std::string_view word) {
    std::size_t i = word.front() == '-' ? 1 : 0;
    long long digits = 0, before_point = -1, first = -1;  // counts and index of mantissa digits
    for (; i < word.size() && word[i] != 'e' && word[i] != 'E'; ++i) {
        if (word[i] == '.') {
            before_point = digits;
            continue;
        }
        if (first < 0 && word[i] != '0') first = digits;
        ++digits;
    }
    if (first < 0) return 0;  // zero is never out of range
    if (before_point < 0) before_point = digits;
    long long exponent = 0;
    for (std::size_t k = i + 1; k < word.size(); ++k)  // saturates: the sign is all that matters
        if (word[k] >= '0' && word[k] <= '9') exponent = std::min(exponent * 10 + (word[k] - '0'), 1000000000LL);
    if (i + 1 < word.size() && word[i + 1] == '-') exponent = -exponent;
    return before_point - 1 - first + exponent;
}

}  // namespace

// float_word and double_word: `beyond` is what an overflow is.
template <class Real>
const char* real_word(std::string_view& word, Real& value, const char* beyond) {
    // from_chars rejects a leading '+'; "+-1" stays "not a number"
    if (word.size() > 1 && word[0] == '+' && word[1] != '-') word.remove_prefix(1);
    value = 0;
    const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (end != word.data() + word.size() || word.empty() || (ec != std::errc() && ec != std::errc::result_out_of_range))
        return "is not a number";
    if (ec == std::errc::result_out_of_range) {
        // Underflow reads as a signed zero (as strtod and most readers do); overflow has no
        // value to stand for it.
        if (decimal_magnitude(word) >= 0) return beyond;
        value = word.front() == '-' ? -Real(0) : Real(0);
    }
    return nullptr;
}

const char* float_word(std::string_view& word, float& value) {
    return real_word(word, value, "is beyond the range of float (about 3.4e38)");
}

const char* double_word(std::string_view& word, double& value) {
    return real_word(word, value, "is beyond the range of double (about 1.8e308)");
}

std::vector<double> parse_doubles(const std::string& path, std::string_view field, std::string_view value,
                                  std::size_t expected) {
    std::vector<double> out;
    for (std::string_view word : split_words(value)) out.push_back(parse_double(path, field, word));
    if (expected != 0 && out.size() != expected)
        fail(path, "field '" + std::string(field) + "' has " + std::to_string(out.size()) + " values, expected " +
                       std::to_string(expected));
    return out;
}

std::vector<std::size_t> parse_sizes(const std::string& path, std::string_view field, std::string_view value) {
    std::vector<std::size_t> out;
    for (std::string_view word : split_words(value)) out.push_back(parse_size(path, field, word));
    return out;
}

}  // namespace voxmesh::io
