// The fragment driver at 4 lane(s), compiled with the project's default flags.
#include "render/lane_driver.h"

namespace reliefsim {
namespace {
struct IsaW4 {};
}  // namespace

void RunBatchW4(const BatchJob& job, LaneBatch& batch) {
    detail::RunBatch<Lanes<4, IsaW4>>(job, batch);
}

float SampleChainW4(const Textures& textures, const float* u, const float* v, int n,
                    int chain, uint64_t* texelReads) {
    return detail::SampleChain<Lanes<4, IsaW4>>(textures, u, v, n, chain, texelReads);
}

}  // namespace reliefsim
