// Built-in procedural height maps: deterministic, periodic (tile seamlessly), any size.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "texture/height_field.h"

namespace reliefsim {

/// Names accepted after "builtin:": shapes (default scene), bumps, steps, noise, and the
/// analytic test fields flat (depth 0.5), ramp (depth = u) and step (depth 0.2 for u < 0.5,
/// else 0.8).
const std::vector<std::string>& BuiltinMapNames();

constexpr int kDefaultBuiltinSize = 256;

/// Makes "builtin:NAME[:SIZE]" (SIZE in [1, 16384], default 256; square). Throws Error on an
/// unknown name or bad size, listing the valid names.
HeightField MakeBuiltinMap(std::string_view spec);

/// Makes a named builtin at width x height.
HeightField MakeBuiltinMap(std::string_view name, int width, int height);

/// 64-bit mix (splitmix64 finaliser): the project's hash for deterministic pseudo-randomness.
inline uint64_t Mix64(uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x;
}

}  // namespace reliefsim
