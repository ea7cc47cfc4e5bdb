// The reference point for the lane sampler: a plain AVX2 loop of dependent
// bilinear fetches over padded texels (texture/padded_texels.h), written with intrinsics
// and nothing else: power-of-two repeat addressing, two 64-bit loads per footprint row,
// no counting, no masks, no sampler state. It runs the same chain as the driver's
// SampleChain (kPacks packs of 8 lanes interleaved, the same uv update), so
// BM_SampleChain/8 over BM_SampleChainRawAvx2 is the counted sampler's cost relative to
// the hand-written loop, measured in one run (docs/benchmarks.md).
#include "bench/raw_chain.h"

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>

#include <algorithm>

namespace reliefsim::bench {

namespace {

inline __m128 LoadPair2(const float* pa, const float* pb) {
    const __m128 lo = _mm_castsi128_ps(_mm_loadu_si64(pa));
    return _mm_loadh_pi(lo, reinterpret_cast<const __m64*>(pb));
}

template <int P>
float Chain(const PaddedTexels& tex, const float* u0, const float* v0, int n, int chain) {
    const float* data = tex.texels.data();
    const int stride = tex.stride;
    const __m256 fw = _mm256_set1_ps(float(tex.width)),
                 fh = _mm256_set1_ps(float(tex.height));
    const __m256i mw = _mm256_set1_epi32(tex.width - 1),
                  mh = _mm256_set1_epi32(tex.height - 1);
    const __m256i vstride = _mm256_set1_epi32(stride);
    const __m256 half = _mm256_set1_ps(0.5f);
    __m256 sum = _mm256_setzero_ps();
    for (int base = 0; base + 8 * P <= n; base += 8 * P) {
        __m256 u[P], v[P];
        for (int j = 0; j < P; ++j) {
            u[j] = _mm256_loadu_ps(u0 + base + 8 * j);
            v[j] = _mm256_loadu_ps(v0 + base + 8 * j);
        }
        for (int k = 0; k < chain; ++k) {
            for (int j = 0; j < P; ++j) {
                const __m256 cu = _mm256_sub_ps(_mm256_mul_ps(u[j], fw), half);
                const __m256 cv = _mm256_sub_ps(_mm256_mul_ps(v[j], fh), half);
                const __m256 flu = _mm256_floor_ps(cu), flv = _mm256_floor_ps(cv);
                const __m256 wu = _mm256_sub_ps(cu, flu), wv = _mm256_sub_ps(cv, flv);
                const __m256i iu = _mm256_and_si256(_mm256_cvttps_epi32(flu), mw);
                const __m256i iv = _mm256_and_si256(_mm256_cvttps_epi32(flv), mh);
                const __m256i at8 = _mm256_add_epi32(_mm256_mullo_epi32(iv, vstride), iu);
                alignas(32) int32_t at[8];
                _mm256_store_si256(reinterpret_cast<__m256i*>(at), at8);
                __m256 t[4];
                for (int row = 0; row < 2; ++row) {
                    const float* p = data + row * stride;
                    const __m256 a = _mm256_set_m128(LoadPair2(p + at[4], p + at[5]),
                                                     LoadPair2(p + at[0], p + at[1]));
                    const __m256 b = _mm256_set_m128(LoadPair2(p + at[6], p + at[7]),
                                                     LoadPair2(p + at[2], p + at[3]));
                    t[2 * row] = _mm256_shuffle_ps(a, b, 0x88);
                    t[2 * row + 1] = _mm256_shuffle_ps(a, b, 0xDD);
                }
                const __m256 r0 = _mm256_fmadd_ps(wu, _mm256_sub_ps(t[1], t[0]), t[0]);
                const __m256 r1 = _mm256_fmadd_ps(wu, _mm256_sub_ps(t[3], t[2]), t[2]);
                const __m256 h = _mm256_fmadd_ps(wv, _mm256_sub_ps(r1, r0), r0);
                u[j] = _mm256_add_ps(
                    _mm256_add_ps(u[j], _mm256_mul_ps(h, _mm256_set1_ps(0.01f))),
                    _mm256_set1_ps(0.0031f));
                v[j] = _mm256_add_ps(v[j], _mm256_set1_ps(0.0017f));
                sum = _mm256_add_ps(sum, h);
            }
        }
    }
    alignas(32) float s[8];
    _mm256_store_ps(s, sum);
    return s[0] + s[1] + s[2] + s[3] + s[4] + s[5] + s[6] + s[7];
}

}  // namespace

bool RawChainAvx2Available() { return true; }

float RawChainAvx2(const PaddedTexels& tex, const float* u, const float* v, int n,
                   int chain, int packs) {
    switch (std::clamp(packs, 1, 4)) {
        case 1:
            return Chain<1>(tex, u, v, n, chain);
        case 2:
            return Chain<2>(tex, u, v, n, chain);
        case 3:
            return Chain<3>(tex, u, v, n, chain);
        default:
            return Chain<4>(tex, u, v, n, chain);
    }
}

}  // namespace reliefsim::bench

#else
namespace reliefsim::bench {
bool RawChainAvx2Available() { return false; }
float RawChainAvx2(const PaddedTexels&, const float*, const float*, int, int, int) {
    return 0.0f;
}
}  // namespace reliefsim::bench
#endif
