// One name table per enum: the spellings of its values, from which parsing, printing,
// error messages and the command line's choices are all derived.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace reliefsim {

/// One spelling of an enum value.
template <typename E>
struct EnumName {
    std::string_view name;
    E value;
};

/// The names of an enum's values, defined once, next to the enum (pbrt's
/// ParseWrapMode/ToString pair, written as data). Names and values are each unique; the
/// constructor refuses a table that breaks this, at compile time for a constexpr table.
/// Names are public spellings (options, files, reports): never change one.
template <typename E, size_t N>
class EnumNames {
  public:
    /// ignoreCase: a name matches whatever its ASCII case ("r" for "R").
    constexpr EnumNames(const EnumName<E> (&entries)[N], bool ignoreCase = false)
        : ignoreCase_(ignoreCase) {
        for (size_t i = 0; i < N; ++i) {
            entries_[i] = entries[i];
            if (entries[i].name.empty()) throw "EnumNames: empty name";
            for (size_t j = 0; j < i; ++j)
                if (Same(entries[j].name, entries[i].name) ||
                    entries[j].value == entries[i].value)
                    throw "EnumNames: duplicate name or value";
        }
    }

    /// The value spelled `s`, or nullopt.
    constexpr std::optional<E> Parse(std::string_view s) const {
        for (const EnumName<E>& e : entries_)
            if (Same(e.name, s)) return e.value;
        return std::nullopt;
    }
    /// The name of `v`; "?" for a value the table lacks (a cast integer).
    constexpr std::string_view Name(E v) const {
        for (const EnumName<E>& e : entries_)
            if (e.value == v) return e.name;
        return "?";
    }
    constexpr const std::array<EnumName<E>, N>& Entries() const { return entries_; }
    constexpr bool IgnoreCase() const { return ignoreCase_; }

    /// The names joined by `separator`: "nearest|bilinear|min4" for help texts.
    std::string Join(std::string_view separator) const {
        std::string r;
        for (const EnumName<E>& e : entries_) {
            if (!r.empty()) r += separator;
            r += e.name;
        }
        return r;
    }
    /// The names quoted, for messages: "\"nearest\", \"bilinear\", \"min4\"".
    std::string QuotedList() const {
        std::string r;
        for (const EnumName<E>& e : entries_)
            r += (r.empty() ? "\"" : ", \"") + std::string(e.name) + "\"";
        return r;
    }
    /// The problem and valid set of a name that is not in the table, for a message whose
    /// subject (an option, a parameter, a file) the caller puts in front:
    /// "\"bicubic\" is unknown; must be one of: \"nearest\", \"bilinear\", \"min4\"".
    std::string Unknown(std::string_view s) const {
        return "\"" + std::string(s) + "\" is unknown; must be one of: " + QuotedList();
    }

  private:
    constexpr bool Same(std::string_view a, std::string_view b) const {
        if (a.size() != b.size()) return false;
        for (size_t i = 0; i < a.size(); ++i)
            if (a[i] != b[i] && !(ignoreCase_ && Lower(a[i]) == Lower(b[i])))
                return false;
        return true;
    }
    static constexpr char Lower(char c) {
        return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c;
    }

    std::array<EnumName<E>, N> entries_{};
    bool ignoreCase_;
};

/// Builds a table with the enum named and the size counted:
/// `MakeEnumNames<WrapMode>({{"repeat", WrapMode::Repeat}, {"clamp", WrapMode::Clamp}})`.
template <typename E, size_t N>
constexpr EnumNames<E, N> MakeEnumNames(const EnumName<E> (&entries)[N],
                                        bool ignoreCase = false) {
    return EnumNames<E, N>(entries, ignoreCase);
}

}  // namespace reliefsim
