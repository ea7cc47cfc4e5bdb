// Strict parsing of numbers given as text (command line, key=value settings, specs): the
// whole text must be the number, and integers are range-checked before they are narrowed.
// And the way back for floats: FloatText, which ParseFiniteFloat reads as the same float.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "core/error.h"

namespace reliefsim {

/// A decimal integer that is the whole of `text` (optional leading '-', no spaces, no
/// '+', no hex); nullopt when it is not one or does not fit in int64.
inline std::optional<int64_t> ParseInt64(std::string_view text) {
    int64_t v = 0;
    auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || ptr != text.data() + text.size() || text.empty())
        return std::nullopt;
    return v;
}

/// True when `text` consists of an optional '-' followed by decimal digits only.
inline bool LooksLikeInteger(std::string_view text) {
    if (!text.empty() && text.front() == '-') text.remove_prefix(1);
    if (text.empty()) return false;
    for (char c : text)
        if (c < '0' || c > '9') return false;
    return true;
}

/// True when the whole of `text` is a decimal floating-point number as std::from_chars
/// reads one (optional '-', digits with an optional point and exponent; also "inf" and
/// "nan", and values beyond double's range): no '+', spaces, hex or digit separators.
inline bool LooksLikeDecimal(std::string_view text) {
    double v = 0.0;
    auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    return !text.empty() && ptr == text.data() + text.size() &&
           (ec == std::errc() || ec == std::errc::result_out_of_range);
}

/// Parses an integer in [lo, hi]; otherwise throws Error "SUBJECT "TEXT": WHY; expected
/// an integer in [lo, hi]". `subject` names the option or parameter (e.g. "--size
/// width").
inline int64_t ParseIntInRange(std::string_view text, int64_t lo, int64_t hi,
                               const std::string& subject) {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    std::optional<int64_t> v = ParseInt64(text);
    if (!v) {
        const std::string why =
            LooksLikeInteger(text) ? "is out of range" : "is not an integer";
        throw Error(subject + " \"" + std::string(text) + "\": " + why +
                    "; expected an integer in " + range);
    }
    if (*v < lo || *v > hi)
        throw Error(subject + " \"" + std::string(text) +
                    "\": is out of range; expected an "
                    "integer in " +
                    range);
    return *v;
}

/// A finite decimal floating-point number that is the whole of `text`; nullopt otherwise
/// (also for "inf", "nan" and values that overflow a float: those that round to infinity,
/// at or beyond 2^128 - 2^103, halfway between the largest float and 2^128; the text of
/// the largest float, "3.40282347e+38", is a little above it and reads as it).
inline std::optional<float> ParseFiniteFloat(std::string_view text) {
    double v = 0.0;
    auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || ptr != text.data() + text.size() || text.empty() ||
        !(std::fabs(v) < 0x1.ffffffp+127))
        return std::nullopt;
    return float(v);
}

/// A float as decimal text that reads back as the same float (nine significant digits,
/// "%.9g": 0.1f is "0.100000001", 30 is "30"): for messages and commands that repeat a
/// value.
inline std::string FloatText(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", double(v));
    return buf;
}

}  // namespace reliefsim
