// The fragment driver at 1 lane(s), compiled with the project's default flags.
#include "render/lane_driver.h"

namespace reliefsim {
namespace {
struct IsaW1 {};
}  // namespace

void RunBatchW1(const BatchJob& job, LaneBatch& batch) {
    detail::RunBatch<Lanes<1, IsaW1>>(job, batch);
}

float SampleChainW1(const Textures& textures, const float* u, const float* v, int n,
                    int chain, uint64_t* texelReads) {
    return detail::SampleChain<Lanes<1, IsaW1>>(textures, u, v, n, chain, texelReads);
}

}  // namespace reliefsim
