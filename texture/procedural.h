// Built-in procedural height maps: deterministic, periodic (tile seamlessly), any size.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/hash.h"  // Mix64, used with the builtins
#include "texture/depth_field.h"

namespace reliefsim {

/// Names accepted after "builtin:": shapes (default scene), bumps, steps, noise, and the
/// analytic test fields flat (depth 0.5), ramp (depth = u) and step (depth 0.2 for u <
/// 0.5, else 0.8).
const std::vector<std::string>& BuiltinMapNames();

constexpr int kDefaultBuiltinSize = 256;

/// Makes "builtin:NAME[:SIZE]" (SIZE in [1, 16384], default 256; square). Throws Error on
/// an unknown name or bad size, listing the valid names.
DepthField MakeBuiltinMap(std::string_view spec);

/// Makes a named builtin at width x height.
DepthField MakeBuiltinMap(std::string_view name, int width, int height);

}  // namespace reliefsim
