// The fragment driver at 16 lanes, compiled for AVX-512 (F, VL, DQ, BW;
// render/CMakeLists.txt).
#include "render/lane_driver.h"

namespace reliefsim {
namespace {
struct IsaAvx512 {};
}  // namespace

void RunBatchW16Avx512(const BatchJob& job, LaneBatch& batch) {
    detail::RunBatch<Lanes<16, IsaAvx512>>(job, batch);
}

float SampleChainW16Avx512(const Textures& textures, const float* u, const float* v,
                           int n, int chain, uint64_t* texelReads) {
    return detail::SampleChain<Lanes<16, IsaAvx512>>(textures, u, v, n, chain,
                                                     texelReads);
}

}  // namespace reliefsim
