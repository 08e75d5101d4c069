// A small JSON writer for the tool's --json output: objects, arrays, numbers, strings, in the order written.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace vkas_tool {

class JsonWriter {
public:
    JsonWriter& beginObject(const char* key = nullptr) { return open(key, '{'); }
    JsonWriter& beginArray(const char* key = nullptr) { return open(key, '['); }
    JsonWriter& end() {
        const char close = stack_.back() == '{' ? '}' : ']';
        stack_.pop_back();
        first_ = false;
        out_ += close;
        return *this;
    }
    JsonWriter& value(const char* key, const std::string& s) {
        prefix(key);
        out_ += quote(s);
        return *this;
    }
    JsonWriter& value(const char* key, const char* s) { return value(key, std::string(s)); }
    JsonWriter& value(const char* key, bool b) {
        prefix(key);
        out_ += b ? "true" : "false";
        return *this;
    }
    JsonWriter& value(const char* key, double d) {
        prefix(key);
        if (!std::isfinite(d)) {
            out_ += "null";  // JSON has no infinities (an empty structure's bounds)
        } else {
            char b[40];
            std::snprintf(b, sizeof b, "%.9g", d);
            out_ += b;
        }
        return *this;
    }
    JsonWriter& value(const char* key, uint64_t v) {
        prefix(key);
        out_ += std::to_string(v);
        return *this;
    }
    JsonWriter& value(const char* key, uint32_t v) { return value(key, uint64_t(v)); }
    JsonWriter& value(const char* key, int64_t v) {
        prefix(key);
        out_ += std::to_string(v);
        return *this;
    }
    template <class T>
    JsonWriter& array(const char* key, const std::vector<T>& values) {
        beginArray(key);
        for (const T& v : values) value(nullptr, v);
        return end();
    }
    const std::string& str() const { return out_; }

private:
    JsonWriter& open(const char* key, char c) {
        prefix(key);
        out_ += c;
        stack_.push_back(c);
        first_ = true;
        return *this;
    }
    void prefix(const char* key) {
        if (!stack_.empty() && !first_) out_ += ',';
        first_ = false;
        if (key) out_ += quote(key) + ':';
    }
    static std::string quote(const std::string& s) {
        std::string r = "\"";
        for (char c : s) {
            if (c == '"' || c == '\\') r += '\\', r += c;
            else if (static_cast<unsigned char>(c) < 0x20) {
                char b[8];
                std::snprintf(b, sizeof b, "\\u%04x", c);
                r += b;
            } else r += c;
        }
        return r + "\"";
    }
    std::string out_;
    std::vector<char> stack_;
    bool first_ = true;
};

}  // namespace vkas_tool
