// The out-of-line counted sample.
#include "texture/sampler.h"

namespace reliefsim {

float SampleCounted(const DepthField& field, const SamplerState& state, float u, float v,
                    FetchCounts* counts) {
    Sampler<true> sampler(field, state, counts);
    return sampler.Sample(glm::vec2(u, v));
}

}  // namespace reliefsim
