// The project's 64-bit hash mix, for deterministic pseudo-randomness and content keys.
#pragma once

#include <cstdint>

namespace reliefsim {

/// 64-bit mix (splitmix64 finaliser).
inline uint64_t Mix64(uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x;
}

}  // namespace reliefsim
