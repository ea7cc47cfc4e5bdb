// The method registry: name -> kernel, its parameters (defaults, ranges) and the maps it
// needs.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "kernels/linear_search.h"

namespace reliefsim {

/// A numeric kernel parameter as given to `--set name=value`.
struct ParamDef {
    std::string name;
    double defaultValue;
    double minValue, maxValue;  ///< inclusive valid range
    bool integer;               ///< integers only (booleans are integers in [0,1])
    std::string help;
};

/// One method of the catalogue.
struct MethodInfo {
    std::string name;    ///< the --method name
    std::string title;   ///< one line
    std::string source;  ///< paper and equation / algorithm numbers
    std::vector<ParamDef> params;
    std::vector<std::string> maps;  ///< derived maps it needs besides the height map
};

/// Every method, in catalogue order.
const std::vector<MethodInfo>& Methods();

/// The method named `name`; throws Error listing the valid names otherwise.
const MethodInfo& FindMethod(std::string_view name);

/// Parameter values by name: every parameter of the method, defaults filled in.
using ParamValues = std::map<std::string, double>;

/// Validates "key=value" settings against the method (unknown key, not a number, not an
/// integer, out of range: one Error naming the culprit and the valid set) and fills
/// defaults.
ParamValues ResolveParams(const MethodInfo& method,
                          const std::vector<std::string>& settings);

/// A configured kernel. Dispatch happens once per frame or tile via std::visit.
using Kernel = std::variant<LinearSearchKernel>;

/// Builds the kernel for a method from resolved parameters.
Kernel MakeKernel(const MethodInfo& method, const ParamValues& values);

}  // namespace reliefsim
