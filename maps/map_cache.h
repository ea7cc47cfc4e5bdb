// Disk cache of generated maps keyed by a hash of the input pixels and the parameters.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "maps/cone_map.h"
#include "maps/cone_map_bilinear.h"

namespace reliefsim {

/// 64-bit key of (height field pixels, size, kind, every parameter that changes the
/// result).
uint64_t ConeMapCacheKey(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                         ConeBounds bounds = ConeBounds::Texel);

/// A cache directory. An entry is "<dir>/<key hex>.rsmap": magic, format version, key,
/// kind, size, channels, payload, and a hash of all of it. Anything that does not check
/// out (truncated, wrong key, wrong version, bad hash) is treated as absent and
/// overwritten.
class MapCache {
  public:
    explicit MapCache(std::string dir) : dir_(std::move(dir)) {}
    std::string PathFor(uint64_t key) const;
    std::optional<ConeMap> Load(uint64_t key) const;
    void Store(uint64_t key, const ConeMap& m) const;  ///< atomic (temp + rename)
    /// Returns the cached map or generates, stores and returns it. *hit tells which.
    /// `bounds` is part of the key (texel-bound keys are those of earlier versions).
    ConeMap GetOrCreate(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                        const std::function<ConeMap()>& make, bool* hit = nullptr,
                        ConeBounds bounds = ConeBounds::Texel) const;

  private:
    std::string dir_;
};

}  // namespace reliefsim
