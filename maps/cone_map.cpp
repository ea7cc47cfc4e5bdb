// Cone maps: names, geometry, offsets, encodings, the bilinear safety pass and
// statistics.
#include "maps/cone_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "core/error.h"
#include "core/huge_pages.h"
#include "core/param_name.h"
#include "maps/cone_map_detail.h"

namespace reliefsim {

void ValidateConeMapParams(const ConeMapParams& p) {
    if (p.searchSteps < 1 || p.searchSteps > 4096)
        throw Error(ParamName("search_steps") + " " + std::to_string(p.searchSteps) +
                    ": out of range; expected 1..4096 (Listing 18-2 uses 128)");
    if (p.stackedCount < 1 || p.stackedCount > 16)
        throw Error(ParamName("stacked_count") + " " + std::to_string(p.stackedCount) +
                    ": out of range; expected 1..16");
    if (!(p.threshold >= 0.0f && p.threshold <= 1.0f))
        throw Error(ParamName("threshold") +
                    ": must be a depth difference in [0, 1]; 0 searches every texel");
    if (p.adaptiveLevels < 0 || p.adaptiveLevels > 12)
        throw Error(ParamName("levels") + " " + std::to_string(p.adaptiveLevels) +
                    ": out of range; expected 0..12");
}

int ChannelCount(ConeKind k, const ConeMapParams& p) {
    switch (k) {
        case ConeKind::Quad:
        case ConeKind::Acm4:
            return 4;
        case ConeKind::Acm8:
            return 8;
        case ConeKind::Stacked:
            return p.stackedCount;
        default:
            return 1;
    }
}

std::vector<std::string> ChannelNames(ConeKind k, const ConeMapParams& p) {
    switch (k) {
        case ConeKind::Quad:
            return {"+x", "-x", "+y", "-y"};
        case ConeKind::Acm4:
            return {"s0", "s1", "s2", "s3"};
        case ConeKind::Acm8:
            return {"s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7"};
        case ConeKind::Stacked: {
            std::vector<std::string> n;
            for (int i = 0; i < p.stackedCount; ++i)
                n.push_back("cone" + std::to_string(i));
            return n;
        }
        case ConeKind::ConeNormal:
            return {"nz"};
        case ConeKind::MinMip:
        case ConeKind::MaxMip:
            return {"depth"};
        default:
            return {"ratio"};
    }
}

namespace detail {

Geometry MakeGeometry(int w, int h) {
    Geometry g;
    g.w = w;
    g.h = h;
    const int gc = std::gcd(w, h);
    const int64_t wq = w / gc, hq = h / gc;
    g.wx = hq * hq;
    g.wy = wq * wq;
    g.scale = double(wq) * double(hq) * double(gc);
    g.halfX = w / 2;
    g.halfY = h / 2;
    return g;
}

float RoundDownStrict(double r) {
    if (!(r < double(kConeRatioCap))) return kConeRatioCap;
    float f = float(r);
    // Round down, then one more ulp when the float sits within double rounding of the
    // value: the stored ratio is then strictly below the exact real ratio (conservative).
    // The next float toward 0 of a positive finite float is its bit pattern minus one
    // (the same as std::nextafter(f, 0), without the library call).
    auto down = [](float x) {
        return std::bit_cast<float>(std::bit_cast<uint32_t>(x) - 1u);
    };
    if (double(f) > r) f = down(f);  // f > r >= 0, so f > 0
    if (double(f) >= r * (1.0 - 1e-14) && f > 0.0f) f = down(f);
    return f;
}

float RatioFromQ(double q, double scale) {
    if (!(q < kInfQ)) return kConeRatioCap;
    return RoundDownStrict(std::sqrt(q) / scale);
}

int SectorCount(ConeKind kind) {
    switch (kind) {
        case ConeKind::Quad:
        case ConeKind::Acm4:
            return 4;
        case ConeKind::Acm8:
            return 8;
        default:
            return 1;
    }
}

namespace {

/// The rays bounding closed sector k of acm4 or acm8 (counter-clockwise from +u, in the
/// directions' space (x * H, y * W)): the sector runs from *a to *b.
void SectorRays(ConeKind kind, int k, const int*& a, const int*& b) {
    static constexpr int kB4[5][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
    static constexpr int kB8[9][2] = {{1, 0},   {1, 1},  {0, 1},  {-1, 1}, {-1, 0},
                                      {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    a = kind == ConeKind::Acm4 ? kB4[k] : kB8[k];
    b = kind == ConeKind::Acm4 ? kB4[k + 1] : kB8[k + 1];
}

/// Whether the direction (vx, vy) lies in the closed wedge from ray a to ray b.
bool InClosedWedge(const int* a, const int* b, int64_t vx, int64_t vy) {
    return a[0] * vy - a[1] * vx >= 0 && vx * b[1] - vy * b[0] >= 0;
}

}  // namespace

uint8_t SectorMask(ConeKind kind, const Geometry& g, int dx, int dy) {
    // Directions in uv space scaled by W*H: (dx * H, dy * W), exact integers.
    const int64_t vx = int64_t(dx) * g.h, vy = int64_t(dy) * g.w;
    switch (kind) {
        case ConeKind::Quad:
            return uint8_t((vx > 0 ? 1 : 0) | (vx < 0 ? 2 : 0) | (vy > 0 ? 4 : 0) |
                           (vy < 0 ? 8 : 0));
        case ConeKind::Acm4:
        case ConeKind::Acm8: {
            const int n = kind == ConeKind::Acm4 ? 4 : 8;
            uint8_t m = 0;
            for (int k = 0; k < n; ++k) {
                const int *a, *b;
                SectorRays(kind, k, a, b);
                if (InClosedWedge(a, b, vx, vy)) m |= uint8_t(1u << k);
            }
            return m;
        }
        default:
            return 1;
    }
}

uint8_t CellSectorMask(ConeKind kind, const Geometry& g, int dx, int dy) {
    // The square of differences in the directions' space (x * H, y * W), exact.
    const int64_t x0 = int64_t(dx - 1) * g.h, x1 = int64_t(dx + 1) * g.h;
    const int64_t y0 = int64_t(dy - 1) * g.w, y1 = int64_t(dy + 1) * g.w;
    switch (kind) {
        case ConeKind::Quad:  // open half planes
            return uint8_t((x1 > 0 ? 1 : 0) | (x0 < 0 ? 2 : 0) | (y1 > 0 ? 4 : 0) |
                           (y0 < 0 ? 8 : 0));
        case ConeKind::Acm4:
        case ConeKind::Acm8: {
            // A closed convex wedge and a rectangle meet iff a corner of the rectangle
            // lies in the wedge or one of the wedge's two rays meets the rectangle
            // (otherwise the rectangle, being connected, lies wholly outside).
            auto rayMeets = [&](const int* a) {
                // t >= 0 with t * a in [x0, x1] x [y0, y1].
                int64_t lo = 0, hi = INT64_MAX;
                auto axis = [&](int ac, int64_t c0, int64_t c1) {
                    if (ac == 0) {
                        if (c0 > 0 || c1 < 0) hi = -1;
                    } else if (ac > 0) {
                        lo = std::max(lo, c0), hi = std::min(hi, c1);
                    } else {
                        lo = std::max(lo, -c1), hi = std::min(hi, -c0);
                    }
                };
                axis(a[0], x0, x1);
                axis(a[1], y0, y1);
                return lo <= hi;
            };
            const int n = kind == ConeKind::Acm4 ? 4 : 8;
            uint8_t m = 0;
            for (int k = 0; k < n; ++k) {
                const int *a, *b;
                SectorRays(kind, k, a, b);
                bool meets = rayMeets(a) || rayMeets(b);
                for (int c = 0; c < 4 && !meets; ++c)
                    meets = InClosedWedge(a, b, (c & 1) ? x1 : x0, (c & 2) ? y1 : y0);
                if (meets) m |= uint8_t(1u << k);
            }
            return m;
        }
        default:
            return 1;
    }
}

namespace {

/// The offset (dx, dy) between texels, or between cells (MakeTiledOffsets); false for
/// the ones left out.
bool MakeOffset(const Geometry& g, ConeKind sectors, bool cells, int dx, int dy,
                Offset& o) {
    if (!cells) {
        if (dx == 0 && dy == 0) return false;
        o = {dx, dy, g.S(dx, dy), SectorMask(sectors, g, dx, dy)};
        return true;
    }
    if (std::abs(dx) <= 1 && std::abs(dy) <= 1) return false;
    o = {dx, dy, g.S(CellGap(dx), CellGap(dy)), CellSectorMask(sectors, g, dx, dy)};
    return true;
}

}  // namespace

std::vector<Offset> MakeOffsets(const Geometry& g, ConeKind sectors, bool cells) {
    std::vector<Offset> offs;
    offs.reserve(size_t(2 * g.halfX + 1) * size_t(2 * g.halfY + 1));
    for (int dy = -g.halfY; dy <= g.halfY; ++dy)
        for (int dx = -g.halfX; dx <= g.halfX; ++dx) {
            Offset o;
            if (MakeOffset(g, sectors, cells, dx, dy, o)) offs.push_back(o);
        }
    return offs;
}

TiledOffsets MakeTiledOffsets(const Geometry& g, ConeKind sectors, bool cells) {
    TiledOffsets to;
    const int nx = (2 * g.halfX + 1 + kTile - 1) / kTile;
    const int ny = (2 * g.halfY + 1 + kTile - 1) / kTile;
    // Sized once: growing by push_back re-copied the (multi-MB) offset list several
    // times.
    to.offsets.reserve(size_t(2 * g.halfX + 1) * size_t(2 * g.halfY + 1));
    to.tiles.reserve(size_t(nx) * size_t(ny));
    for (int ty = 0; ty < ny; ++ty)
        for (int tx = 0; tx < nx; ++tx) {
            OffsetTile t;
            t.ox = -g.halfX + tx * kTile;
            t.oy = -g.halfY + ty * kTile;
            t.begin = int(to.offsets.size());
            t.minS = std::numeric_limits<int64_t>::max();
            t.mask = 0;
            for (int dy = t.oy; dy < std::min(t.oy + kTile, g.halfY + 1); ++dy)
                for (int dx = t.ox; dx < std::min(t.ox + kTile, g.halfX + 1); ++dx) {
                    Offset o;
                    if (!MakeOffset(g, sectors, cells, dx, dy, o)) continue;
                    to.offsets.push_back(o);
                    t.minS = std::min(t.minS, o.s);
                    t.mask |= o.mask;
                }
            t.end = int(to.offsets.size());
            if (t.end > t.begin) to.tiles.push_back(t);
        }
    std::stable_sort(
        to.tiles.begin(), to.tiles.end(),
        [](const OffsetTile& a, const OffsetTile& b) { return a.minS < b.minS; });
    // Super-tiles: group the (sorted) tiles by 32x32 window, keeping their order in a
    // group.
    const int span = kTile * kSuperTile;
    const int sxCount = (2 * g.halfX + 1 + span - 1) / span;
    std::vector<std::vector<int>> groups(size_t(sxCount) *
                                         size_t((2 * g.halfY + 1 + span - 1) / span));
    for (size_t t = 0; t < to.tiles.size(); ++t) {
        const int sx = (to.tiles[t].ox + g.halfX) / span,
                  sy = (to.tiles[t].oy + g.halfY) / span;
        groups[size_t(sy) * size_t(sxCount) + size_t(sx)].push_back(int(t));
    }
    for (size_t gi = 0; gi < groups.size(); ++gi) {
        if (groups[gi].empty()) continue;
        OffsetSuperTile st;
        st.first = int(to.superOrder.size());
        st.ox = -g.halfX + int(gi % size_t(sxCount)) * span;
        st.oy = -g.halfY + int(gi / size_t(sxCount)) * span;
        st.minS = std::numeric_limits<int64_t>::max();
        st.mask = 0;
        for (int t : groups[gi]) {
            to.superOrder.push_back(t);
            st.minS = std::min(st.minS, to.tiles[size_t(t)].minS);
            st.mask |= to.tiles[size_t(t)].mask;
        }
        st.last = int(to.superOrder.size());
        to.supers.push_back(st);
    }
    std::stable_sort(to.supers.begin(), to.supers.end(),
                     [](const OffsetSuperTile& a, const OffsetSuperTile& b) {
                         return a.minS < b.minS;
                     });
    return to;
}

/// Writes into `out` through `rows` (both resized, their storage reused: fresh pages are
/// expensive on a VM, and the dynamic maps call this every frame).
template <class T, class Op>
void WindowReduceInto(const std::vector<T>& v, int W, int H, int C, int k, int step,
                      Op op, std::vector<T>& rows, std::vector<T>& out) {
    const size_t rowLen = size_t(W) * size_t(C);
    // One separable pass: along x or y, k samples `step` apart, wrapped. Whole rows at a
    // time: along y, a row of the result is the op of k rows of the input; along x, of
    // the input row and its k - 1 rotations (by step, 2 step, ... texels, in two
    // pieces). Flat loops over W * C values (vectors for any C), each value taking its k
    // samples in order, as one texel at a time would.
    auto pass = [&](const std::vector<T>& in, std::vector<T>& out, bool alongX) {
        tbb::parallel_for(
            tbb::blocked_range<int>(0, H, 1), [&](const tbb::blocked_range<int>& r) {
                for (int j = r.begin(); j < r.end(); ++j) {
                    T* o = &out[size_t(j) * rowLen];
                    const T* row = &in[size_t(j) * rowLen];
                    std::copy(row, row + rowLen, o);
                    for (int a = 1; a < k; ++a) {
                        if (alongX) {
                            // o[e] against row[(e + s) mod rowLen], s = the rotation.
                            const size_t s = size_t(Wrap(a * step, W)) * size_t(C);
                            const size_t n1 = rowLen - s;
                            for (size_t e = 0; e < n1; ++e) o[e] = op(o[e], row[e + s]);
                            for (size_t e = n1; e < rowLen; ++e)
                                o[e] = op(o[e], row[e - n1]);
                        } else {
                            const T* next = &in[size_t(Wrap(j + a * step, H)) * rowLen];
                            for (size_t e = 0; e < rowLen; ++e) o[e] = op(o[e], next[e]);
                        }
                    }
                }
            });
    };
    ResizeOnHugePages(rows, v.size());
    ResizeOnHugePages(out, v.size());
    pass(v, rows, true);
    pass(rows, out, false);
}

template <class T, class Op>
std::vector<T> WindowReduce(const std::vector<T>& v, int W, int H, int C, int k, int step,
                            Op op) {
    std::vector<T> rows, out;
    WindowReduceInto(v, W, H, C, k, step, op, rows, out);
    return out;
}

template <class T>
std::vector<T> WindowMinima(const std::vector<T>& v, int W, int H, int C, int k,
                            int step) {
    return WindowReduce(v, W, H, C, k, step, [](T a, T b) { return std::min(a, b); });
}

std::vector<float> WindowMaxima(const std::vector<float>& v, int W, int H, int k,
                                int step) {
    return WindowReduce(v, W, H, 1, k, step,
                        [](float a, float b) { return std::max(a, b); });
}

template std::vector<float> WindowMinima(const std::vector<float>&, int, int, int, int,
                                         int);
template std::vector<uint8_t> WindowMinima(const std::vector<uint8_t>&, int, int, int,
                                           int, int);

void MakeSearchWindows(const DepthField& hf, SearchWindows& out) {
    auto mn = [](float a, float b) { return std::min(a, b); };
    WindowReduceInto(hf.depth, hf.width, hf.height, 1, kTile, 1, mn, out.scratch,
                     out.win8);
    WindowReduceInto(out.win8, hf.width, hf.height, 1, kSuperTile, kTile, mn, out.scratch,
                     out.win32);
}

float CheckedMinDepth(const DepthField& hf) {
    if (hf.width <= 0 || hf.height <= 0)
        throw Error("height map \"" + hf.name + "\": zero size (" +
                    std::to_string(hf.width) + "x" + std::to_string(hf.height) +
                    "); expected at least 1x1");
    if (hf.depth.size() != size_t(hf.width) * size_t(hf.height))
        throw Error("height map \"" + hf.name + "\": has " +
                    std::to_string(hf.depth.size()) + " depths, expected width*height");
    ValidateDepthField(hf);
    float m = hf.depth[0];
    for (float d : hf.depth) m = std::min(m, d);
    return m;
}

}  // namespace detail

float DecodeRatio(uint16_t code, ConeEncoding enc) {
    switch (enc) {
        case ConeEncoding::U8:
            return Unorm8ToFloat(uint8_t(code));
        case ConeEncoding::U8Sqrt: {
            const float s = Unorm8ToFloat(uint8_t(code));
            return s * s;
        }
        case ConeEncoding::U16:
            return float(code) * float(1.0 / 65535.0);
        default:
            return float(code);
    }
}

uint16_t EncodeRatio(float ratio, ConeEncoding enc) {
    if (!(ratio > 0.0f)) return 0;
    const float r = std::min(ratio, 1.0f);
    int code = 0, maxCode = enc == ConeEncoding::U16 ? 65535 : 255;
    switch (enc) {
        case ConeEncoding::U8:
            code = int(std::floor(double(r) * 255.0));
            break;
        case ConeEncoding::U8Sqrt:
            code = int(std::floor(std::sqrt(double(r)) * 255.0));
            break;
        case ConeEncoding::U16:
            code = int(std::floor(double(r) * 65535.0));
            break;
        default:
            return 0;
    }
    code = std::clamp(code, 0, maxCode);
    // The decoder's float arithmetic may land above the ratio: step down until it does
    // not.
    while (code > 0 && DecodeRatio(uint16_t(code), enc) > ratio) --code;
    while (code < maxCode && DecodeRatio(uint16_t(code + 1), enc) <= ratio) ++code;
    return uint16_t(code);
}

ConeMap QuantizeConeMap(const ConeMap& m, ConeEncoding enc,
                        std::vector<uint16_t>* codes) {
    ConeMap out = m;
    if (codes) codes->assign(m.values.size(), 0);
    if (enc == ConeEncoding::Float) return out;
    uint16_t* code = codes ? codes->data() : nullptr;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m.values.size(), size_t(1) << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) {
                              const uint16_t c = EncodeRatio(m.values[i], enc);
                              out.values[i] = DecodeRatio(c, enc);
                              if (code) code[i] = c;
                          }
                      });
    return out;
}

const ConeMap& StoredConeMap(const ConeMap& m, ConeEncoding enc, ConeMap& scratch) {
    if (enc == ConeEncoding::Float) return m;
    scratch = QuantizeConeMap(m, enc);
    return scratch;
}

ConeMap BilinearSafetyPass(const ConeMap& m) {
    ConeMap out = m;
    const int W = m.width, H = m.height, C = m.channels;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            for (int c = 0; c < C; ++c) {
                float v = m.At(i, j, c);
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        v = std::min(
                            v, m.At(detail::Wrap(i + dx, W), detail::Wrap(j + dy, H), c));
                out.values[(size_t(j) * size_t(W) + size_t(i)) * size_t(C) + size_t(c)] =
                    v;
            }
    return out;
}

ConeMapStats ComputeConeMapStats(const ConeMap& m, int bins) {
    ConeMapStats s;
    s.histogram.assign(size_t(std::max(bins, 1)), 0);
    double sum = 0;
    bool first = true;
    for (float v : m.values) {
        if (v >= kConeRatioCap) {
            ++s.nUnbounded;
            continue;
        }
        const double d = double(v);
        if (first) {
            s.minRatio = s.maxRatio = d;
            first = false;
        }
        s.minRatio = std::min(s.minRatio, d);
        s.maxRatio = std::max(s.maxRatio, d);
        sum += d;
        ++s.nValues;
        int b = int(std::floor(d * double(s.histogram.size())));
        b = std::clamp(b, 0, int(s.histogram.size()) - 1);
        ++s.histogram[size_t(b)];
    }
    s.meanRatio = s.nValues ? sum / double(s.nValues) : 0.0;
    return s;
}

std::string ConeMapStatsJson(const ConeMap& m, const ConeMapStats& s, ConeEncoding enc) {
    nlohmann::json j;
    j["kind"] = std::string(ToString(m.kind));
    j["encoding"] = std::string(ToString(enc));
    j["width"] = m.width;
    j["height"] = m.height;
    j["channels"] = m.channels;
    j["min"] = s.minRatio;
    j["mean"] = s.meanRatio;
    j["max"] = s.maxRatio;
    j["values"] = s.nValues;
    j["unbounded"] = s.nUnbounded;
    j["histogram_range"] = {0.0, 1.0};
    j["histogram"] = s.histogram;
    return j.dump(2);
}

DepthField MakeSinusoidMap(int width, int height, float t) {
    DepthField hf;
    FillSinusoidMap(hf, width, height, t);
    return hf;
}

void FillSinusoidMap(DepthField& hf, int width, int height, float t) {
    hf.width = width;
    hf.height = height;
    hf.name = "sinusoids";
    hf.depth8.clear();
    hf.depth.resize(size_t(width) * size_t(height));
    constexpr double kTwoPi = 6.283185307179586;
    // (cycles in u, cycles in v, speed in cycles/s, amplitude): integer cycles keep it
    // periodic.
    static constexpr double kWaves[4][4] = {
        {2, 1, 0.5, 0.20}, {-1, 3, 0.8, 0.12}, {4, -2, 1.1, 0.07}, {1, 5, 0.3, 0.05}};
    // sin(a + b) = sin a cos b + cos a sin b: per-column and per-row tables, no sin per
    // texel.
    std::vector<double> su(size_t(width) * 4), cu(size_t(width) * 4),
        sv(size_t(height) * 4), cv(size_t(height) * 4);
    for (int w = 0; w < 4; ++w) {
        for (int i = 0; i < width; ++i) {
            const double a = kTwoPi * kWaves[w][0] * ((i + 0.5) / width);
            su[size_t(i) * 4 + size_t(w)] = std::sin(a);
            cu[size_t(i) * 4 + size_t(w)] = std::cos(a);
        }
        for (int j = 0; j < height; ++j) {
            const double b =
                kTwoPi * (kWaves[w][1] * ((j + 0.5) / height) - kWaves[w][2] * double(t));
            sv[size_t(j) * 4 + size_t(w)] = kWaves[w][3] * std::sin(b);
            cv[size_t(j) * 4 + size_t(w)] = kWaves[w][3] * std::cos(b);
        }
    }
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            double h = 0;
            for (size_t w = 0; w < 4; ++w)
                h += su[size_t(i) * 4 + w] * cv[size_t(j) * 4 + w] +
                     cu[size_t(i) * 4 + w] * sv[size_t(j) * 4 + w];
            hf.depth[size_t(j) * size_t(width) + size_t(i)] = float(0.5 + h);
        }
}

}  // namespace reliefsim
