#include "texture/padded_texels.h"

#include "core/error.h"
#include "texture/lane_sampler.h"

namespace reliefsim {

PaddedTexels PadTexels(const DepthField& field, WrapMode wrap) {
    RS_CHECK(!field.Empty());
    PaddedTexels p;
    p.width = field.width;
    p.height = field.height;
    p.stride = field.width + 1;
    p.wrap = wrap;
    p.texels.resize(size_t(p.stride) * size_t(field.height + 1));
    const bool repeat = wrap == WrapMode::Repeat;
    for (int j = 0; j <= field.height; ++j) {
        const int sj = j < field.height ? j : (repeat ? 0 : field.height - 1);
        float* row = p.texels.data() + size_t(j) * size_t(p.stride);
        for (int i = 0; i < field.width; ++i) row[i] = field.At(i, sj);
        row[field.width] = field.At(repeat ? 0 : field.width - 1, sj);
    }
    return p;
}

void BindConeChannel(Textures& t, DepthField cone, bool squared) {
    RS_CHECK(t.depth && cone.width == t.depth->width && cone.height == t.depth->height);
    t.conePadded = std::make_shared<const PaddedTexels>(PadTexels(cone, t.sampler.wrap));
    t.cone = std::make_shared<const DepthField>(std::move(cone));
    t.coneSquared = squared;
}

}  // namespace reliefsim
