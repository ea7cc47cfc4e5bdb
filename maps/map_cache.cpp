// Disk cache of generated maps: content-hash keys, verified entries, atomic writes.
#include "maps/map_cache.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <vector>

#include "core/output_set.h"
#include "core/param_name.h"
#include "texture/procedural.h"

namespace reliefsim {

namespace {
constexpr uint64_t kMagic = 0x3170616d53455252ull;  // "RRESmap1"
constexpr uint32_t kVersion = 1;  // bump when a generator's output changes

uint64_t HashBytes(uint64_t h, const void* data, size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        std::memcpy(&w, b + i, 8);
        h = Mix64(h ^ w);
    }
    uint64_t tail = 0;
    std::memcpy(&tail, b + i, n - i);
    return Mix64(h ^ tail ^ (uint64_t(n) << 56));
}

template <class T>
uint64_t HashValue(uint64_t h, const T& v) {
    return HashBytes(h, &v, sizeof(v));
}
}  // namespace

uint64_t ConeMapCacheKey(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                         ConeBounds bounds) {
    uint64_t h = Mix64(kMagic ^ kVersion);
    h = HashValue(h, hf.width);
    h = HashValue(h, hf.height);
    h = HashBytes(h, hf.depth.data(), hf.depth.size() * sizeof(float));
    h = HashValue(h, int(kind));
    h = HashValue(h, p.searchSteps);
    h = HashValue(h, p.stackedCount);
    h = HashValue(h, int(p.relaxed));
    h = HashValue(h, int(p.normal));
    h = HashValue(h, int(p.adaptive));
    h = HashValue(h, p.threshold);
    h = HashValue(h, p.adaptiveLevels);
    if (bounds != ConeBounds::Texel) h = HashValue(h, int(bounds));
    return h;
}

std::string MapCache::PathFor(uint64_t key) const {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%016llx.rsmap", static_cast<unsigned long long>(key));
    return (std::filesystem::path(dir_) / buf).string();
}

std::optional<ConeMap> MapCache::Load(uint64_t key) const {
    std::ifstream f(PathFor(key), std::ios::binary);
    if (!f) return std::nullopt;
    std::vector<char> bytes((std::istreambuf_iterator<char>(f)),
                            std::istreambuf_iterator<char>());
    constexpr size_t kHeader = 8 + 4 + 8 + 4 * 4;
    if (bytes.size() < kHeader + 8) return std::nullopt;
    uint64_t magic, k, sum;
    uint32_t version;
    int32_t kind, w, h, c;
    size_t o = 0;
    auto rd = [&](void* dst, size_t n) {
        std::memcpy(dst, bytes.data() + o, n);
        o += n;
    };
    rd(&magic, 8);
    rd(&version, 4);
    rd(&k, 8);
    rd(&kind, 4);
    rd(&w, 4);
    rd(&h, 4);
    rd(&c, 4);
    if (magic != kMagic || version != kVersion || k != key || w <= 0 || h <= 0 ||
        c <= 0 || c > 16 || kind < 0 || kind > int(ConeKind::MaxMip))
        return std::nullopt;
    const size_t payload = size_t(w) * size_t(h) * size_t(c) * sizeof(float);
    if (bytes.size() != kHeader + payload + 8) return std::nullopt;
    std::memcpy(&sum, bytes.data() + kHeader + payload, 8);
    if (sum != HashBytes(kMagic, bytes.data(), kHeader + payload)) return std::nullopt;
    ConeMap m;
    m.kind = ConeKind(kind);
    m.width = w;
    m.height = h;
    m.channels = c;
    m.values.resize(payload / sizeof(float));
    std::memcpy(m.values.data(), bytes.data() + kHeader, payload);
    return m;
}

void MapCache::Store(uint64_t key, const ConeMap& m) const {
    std::vector<char> bytes;
    auto wr = [&](const void* src, size_t n) {
        const char* s = static_cast<const char*>(src);
        bytes.insert(bytes.end(), s, s + n);
    };
    const int32_t kind = int32_t(m.kind), w = m.width, h = m.height, c = m.channels;
    wr(&kMagic, 8);
    wr(&kVersion, 4);
    wr(&key, 8);
    wr(&kind, 4);
    wr(&w, 4);
    wr(&h, 4);
    wr(&c, 4);
    wr(m.values.data(), m.values.size() * sizeof(float));
    const uint64_t sum = HashBytes(kMagic, bytes.data(), bytes.size());
    wr(&sum, 8);
    // A missing cache folder is created; the entry appears complete or not at all.
    WriteFileAtomically(PathFor(key), std::string_view(bytes.data(), bytes.size()),
                        ParamName("cache_dir") + " \"" + dir_ + "\"");
}

ConeMap MapCache::GetOrCreate(const DepthField& hf, ConeKind kind, const ConeMapParams& p,
                              const std::function<ConeMap()>& make, bool* hit,
                              ConeBounds bounds) const {
    const uint64_t key = ConeMapCacheKey(hf, kind, p, bounds);
    if (auto m = Load(key); m && m->width == hf.width && m->height == hf.height) {
        if (hit) *hit = true;
        return *m;
    }
    if (hit) *hit = false;
    ConeMap m = make();
    Store(key, m);
    return m;
}

}  // namespace reliefsim
