// Error type for bad input, and the checks used for invariants.
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace reliefsim {

/// Thrown by library code for bad input (files, parameters, options). Only main() prints
/// it. Message format: "subject: problem; expected/valid set; hint".
class Error : public std::runtime_error {
  public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// Text of several lines (third-party messages carry one line per libpng/libtiff report)
/// as one line: lines trimmed of blanks and joined with "; ", repeated lines dropped,
/// and, when maxChars > 0, cut to that length with "...".
inline std::string OneLine(const std::string& text, size_t maxChars = 0) {
    std::string out, line;
    std::vector<std::string> seen;
    auto flush = [&] {
        const size_t b = line.find_first_not_of(" \t\r"),
                     e = line.find_last_not_of(" \t\r");
        if (b != std::string::npos) {
            std::string l = line.substr(b, e - b + 1);
            if (std::find(seen.begin(), seen.end(), l) == seen.end()) {
                if (!out.empty()) out += "; ";
                out += l;
                seen.push_back(std::move(l));
            }
        }
        line.clear();
    };
    for (char c : text) {
        if (c == '\n')
            flush();
        else
            line += c;
    }
    flush();
    if (maxChars > 0 && out.size() > maxChars) out = out.substr(0, maxChars) + "...";
    return out;
}

namespace detail {
template <typename A, typename B>
[[noreturn]] void CheckFailed(const char* file, int line, const char* expr, const A& a,
                              const B& b) {
    std::ostringstream s;
    s << file << ":" << line << ": check failed: " << expr << " (" << a << " vs " << b
      << ")";
    std::fprintf(stderr, "%s\n", s.str().c_str());
    std::abort();
}
}  // namespace detail

}  // namespace reliefsim

#define RS_CHECK(cond)                                                            \
    do {                                                                          \
        if (!(cond)) {                                                            \
            std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, \
                         #cond);                                                  \
            std::abort();                                                         \
        }                                                                         \
    } while (0)

#define RS_CHECK_OP(a, op, b)                                                            \
    do {                                                                                 \
        if (!((a)op(b)))                                                                 \
            ::reliefsim::detail::CheckFailed(__FILE__, __LINE__, #a " " #op " " #b, (a), \
                                             (b));                                       \
    } while (0)
#define RS_CHECK_EQ(a, b) RS_CHECK_OP(a, ==, b)
#define RS_CHECK_LE(a, b) RS_CHECK_OP(a, <=, b)
#define RS_CHECK_LT(a, b) RS_CHECK_OP(a, <, b)

/// Forces inlining of small hot functions (samplers, wrap arithmetic) that GCC would
/// otherwise leave as calls inside kernel loops.
#if defined(__GNUC__)
#define RS_INLINE inline __attribute__((always_inline))
#else
#define RS_INLINE inline
#endif
/// Keeps a large, rarely run function out of line (its callers' builds stay fast).
#if defined(__GNUC__)
#define RS_NOINLINE __attribute__((noinline))
#else
#define RS_NOINLINE
#endif

#ifdef NDEBUG
#define RS_DCHECK(cond) ((void)0)
#else
#define RS_DCHECK(cond) RS_CHECK(cond)
#endif
