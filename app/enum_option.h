// Command-line options whose values are the names of an enum (core/enum_names.h).
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>

#include "core/enum_names.h"

namespace reliefsim {

/// The name of the validator AddEnumOption gives its option (for code that looks it up).
inline constexpr const char* kEnumValidatorName = "enum-names";

/// Adds `flag` to cmd, bound to `field`. Its values are the table's names, shown in the
/// help as `nearest|bilinear|min4` with the field's value at this call as the default;
/// anything else is refused with one line that names the option, the value and the
/// names: `--filter: "bicubic" is unknown; must be one of: "nearest", "bilinear",
/// "min4"`.
template <typename E, size_t N>
CLI::Option* AddEnumOption(CLI::App* cmd, const std::string& flag, E& field,
                           const EnumNames<E, N>& names, const std::string& help) {
    std::map<std::string, E> nameToValue;
    for (const EnumName<E>& e : names.Entries())
        nameToValue.emplace(std::string(e.name), e.value);
    CLI::CheckedTransformer::filter_fn_t filter;
    if (names.IgnoreCase()) filter = CLI::ignore_case;
    const CLI::CheckedTransformer toValue(nameToValue, filter);
    // The names are checked against the table before CheckedTransformer runs: on its own
    // it also accepts the enum's integer ("--filter 0") and words a refusal as "Check
    // bicubic value in {bilinear->1,min4->2,nearest->0} OR {1,2,0} FAILED".
    const CLI::Validator validator(
        [names, toValue](std::string& text) {
            if (!names.Parse(text)) return names.Unknown(text);
            return toValue(text);
        },
        /*validator_desc=*/"");
    return cmd->add_option(flag, field, help)
        ->transform(validator, kEnumValidatorName)
        ->type_name(names.Join("|"))
        ->default_str(std::string(names.Name(field)));
}

}  // namespace reliefsim
