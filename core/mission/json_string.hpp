// The one JSON string writer in C++: a quoted, escaped JSON string, UTF-8 as it is (the
// mission image's canonical form, json.dumps(..., ensure_ascii=False); trace lines and
// logs use the same). Header-only so that keel_fsm, which needs only the mission model's
// headers, writes its trace lines with it too.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace keel::mission {

inline void append_json_string(std::string& out, std::string_view text) {
    out += '"';
    for (const char c : text) {
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\b': out += "\\b"; break;
            case '\f': out += "\\f"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    char buffer[8];
                    std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(c));
                    out += buffer;
                } else {
                    out += c;
                }
        }
    }
    out += '"';
}

}  // namespace keel::mission
