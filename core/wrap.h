// Repeat addressing: the project's one integer wrap, for texel indices and cells.
#pragma once

#include <concepts>

namespace reliefsim {

/// i mod n in [0, n) for any i (n > 0): the texel that repeat addressing reads at i.
template <std::signed_integral T>
constexpr T Wrap(T i, T n) {
    const T r = i % n;
    return r < 0 ? r + n : r;
}

static_assert(Wrap(-1, 4) == 3 && Wrap(4, 4) == 0 && Wrap(-8, 4) == 0 && Wrap(5, 4) == 1);

}  // namespace reliefsim
