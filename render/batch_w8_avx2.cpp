// The fragment driver at 8 lanes, compiled for AVX2 with FMA (render/CMakeLists.txt).
#include "render/lane_driver.h"

namespace reliefsim {
namespace {
struct IsaAvx2 {};
}  // namespace

void RunBatchW8Avx2(const BatchJob& job, LaneBatch& batch) {
    detail::RunBatch<Lanes<8, IsaAvx2>>(job, batch);
}

float SampleChainW8Avx2(const Textures& textures, const float* u, const float* v, int n,
                        int chain, uint64_t* texelReads) {
    return detail::SampleChain<Lanes<8, IsaAvx2>>(textures, u, v, n, chain, texelReads);
}

}  // namespace reliefsim
