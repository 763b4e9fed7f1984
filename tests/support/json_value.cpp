#include "json_value.hpp"

#include <cstdlib>
#include <stdexcept>

namespace vmtest {

namespace {

class Reader {
public:
    explicit Reader(const std::string& text) : s_(text) {}

    JsonValue document() {
        JsonValue v = value();
        skip_space();
        if (at_ != s_.size()) fail("text after the value");
        return v;
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw std::runtime_error("JSON: " + what + " at byte " + std::to_string(at_));
    }

    void skip_space() {
        while (at_ < s_.size() && (s_[at_] == ' ' || s_[at_] == '\n' || s_[at_] == '\r' || s_[at_] == '\t')) ++at_;
    }

    char peek() {
        skip_space();
        if (at_ >= s_.size()) fail("unexpected end");
        return s_[at_];
    }

    void expect(char c) {
        if (peek() != c) fail(std::string("expected '") + c + "'");
        ++at_;
    }

    bool word(const std::string& w) {
        if (s_.compare(at_, w.size(), w) != 0) return false;
        at_ += w.size();
        return true;
    }

    std::string string() {
        expect('"');
        std::string out;
        while (true) {
            if (at_ >= s_.size()) fail("unterminated string");
            const char c = s_[at_++];
            if (c == '"') return out;
            if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
            if (c == '\\') {
                if (at_ >= s_.size()) fail("unterminated escape");
                const char e = s_[at_++];
                switch (e) {
                    case '"': case '\\': case '/': out += e; break;
                    case 'n': out += '\n'; break;
                    case 't': out += '\t'; break;
                    case 'r': out += '\r'; break;
                    case 'b': out += '\b'; break;
                    case 'f': out += '\f'; break;
                    default: fail("unsupported escape");
                }
            } else {
                out += c;
            }
        }
    }

    JsonValue value() {
        JsonValue v;
        const char c = peek();
        if (c == '{') {
            v.kind = JsonValue::Kind::Object;
            ++at_;
            if (peek() == '}') return ++at_, v;
            while (true) {
                const std::string key = string();
                expect(':');
                if (!v.members.emplace(key, value()).second) fail("repeated key '" + key + "'");
                if (peek() == '}') return ++at_, v;
                expect(',');
            }
        }
        if (c == '[') {
            v.kind = JsonValue::Kind::Array;
            ++at_;
            if (peek() == ']') return ++at_, v;
            while (true) {
                v.items.push_back(value());
                if (peek() == ']') return ++at_, v;
                expect(',');
            }
        }
        if (c == '"') {
            v.kind = JsonValue::Kind::String;
            v.text = string();
            return v;
        }
        if (word("true") || word("false")) {
            v.kind = JsonValue::Kind::Bool;
            v.boolean = s_[at_ - 4] == 't';  // "true" was the word just read
            return v;
        }
        if (word("null")) return v;
        // A number as JSON's grammar has it: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?
        const std::size_t start = at_;
        if (s_[at_] == '-') ++at_;
        const auto digits = [&] {
            const std::size_t first = at_;
            while (at_ < s_.size() && s_[at_] >= '0' && s_[at_] <= '9') ++at_;
            return at_ - first;
        };
        const std::size_t int_start = at_;
        const std::size_t int_digits = digits();
        if (int_digits == 0) fail("not a value");
        if (int_digits > 1 && s_[int_start] == '0') fail("a number with a leading zero");
        if (at_ < s_.size() && s_[at_] == '.') {
            ++at_;
            if (digits() == 0) fail("no digits after a decimal point");
        }
        if (at_ < s_.size() && (s_[at_] == 'e' || s_[at_] == 'E')) {
            ++at_;
            if (at_ < s_.size() && (s_[at_] == '+' || s_[at_] == '-')) ++at_;
            if (digits() == 0) fail("no digits in an exponent");
        }
        const std::string number = s_.substr(start, at_ - start);
        char* end = nullptr;
        v.kind = JsonValue::Kind::Number;
        v.number = std::strtod(number.c_str(), &end);
        if (end != number.c_str() + number.size()) fail("malformed number '" + number + "'");
        return v;
    }

    const std::string& s_;
    std::size_t at_ = 0;
};

}  // namespace

const JsonValue& JsonValue::operator[](const std::string& key) const {
    if (kind != Kind::Object) throw std::runtime_error("JSON: not an object (member '" + key + "')");
    const auto it = members.find(key);
    if (it == members.end()) throw std::runtime_error("JSON: no member '" + key + "'");
    return it->second;
}

const JsonValue& JsonValue::operator[](std::size_t index) const {
    if (kind != Kind::Array || index >= items.size())
        throw std::runtime_error("JSON: no item " + std::to_string(index));
    return items[index];
}

JsonValue parse_json(const std::string& text) { return Reader(text).document(); }

}  // namespace vmtest
