// Small helpers shared by the fuzz harnesses (fuzz/*_fuzzer.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace reliefsim::fuzz {

/// The input split on '\n' (a trailing '\r' is kept: it is part of the fuzzed text). An
/// empty input gives no lines; a final empty line after the last '\n' is dropped.
inline std::vector<std::string> SplitLines(const uint8_t* data, size_t size) {
    std::vector<std::string> lines;
    std::string_view text(reinterpret_cast<const char*>(data), size);
    while (!text.empty()) {
        const size_t nl = text.find('\n');
        lines.emplace_back(text.substr(0, nl));
        if (nl == std::string_view::npos) break;
        text.remove_prefix(nl + 1);
    }
    return lines;
}

}  // namespace reliefsim::fuzz
