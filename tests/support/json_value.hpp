// A deliberately small JSON reader for tests (glTF's JSON chunk): objects, arrays, strings
// without \u escapes, numbers as double, true/false/null. Throws std::runtime_error on
// anything else, or on text after the value.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace vmtest {

struct JsonValue {
    enum class Kind { Null, Bool, Number, String, Array, Object } kind = Kind::Null;
    bool boolean = false;
    double number = 0;
    std::string text;
    std::vector<JsonValue> items;              // Array
    std::map<std::string, JsonValue> members;  // Object (a repeated key is an error)

    bool has(const std::string& key) const { return kind == Kind::Object && members.count(key) > 0; }
    // The member or item asked for; std::runtime_error where there is none.
    const JsonValue& operator[](const std::string& key) const;
    const JsonValue& operator[](std::size_t index) const;
    std::size_t size() const { return kind == Kind::Array ? items.size() : members.size(); }
};

JsonValue parse_json(const std::string& text);

}  // namespace vmtest
