// Names of sampler enums.
#include "texture/sampler.h"

namespace reliefsim {

std::string_view ToString(Filter f) {
    switch (f) {
        case Filter::Nearest:
            return "nearest";
        case Filter::Bilinear:
            return "bilinear";
        case Filter::Min4:
            return "min4";
    }
    return "?";
}
std::string_view ToString(WrapMode w) {
    return w == WrapMode::Clamp ? "clamp" : "repeat";
}

std::string_view ToString(Precision p) {
    switch (p) {
        case Precision::Float:
            return "float";
        case Precision::Llvmpipe8:
            return "llvmpipe8";
        case Precision::Gpu8:
            return "gpu8";
    }
    return "?";
}

std::optional<Precision> ParsePrecision(std::string_view s) {
    if (s == "float") return Precision::Float;
    if (s == "llvmpipe8") return Precision::Llvmpipe8;
    if (s == "gpu8") return Precision::Gpu8;
    return std::nullopt;
}

std::optional<Filter> ParseFilter(std::string_view s) {
    if (s == "nearest") return Filter::Nearest;
    if (s == "bilinear") return Filter::Bilinear;
    if (s == "min4") return Filter::Min4;
    return std::nullopt;
}
std::optional<WrapMode> ParseWrapMode(std::string_view s) {
    if (s == "repeat") return WrapMode::Repeat;
    if (s == "clamp") return WrapMode::Clamp;
    return std::nullopt;
}

}  // namespace reliefsim

namespace reliefsim {

float SampleCounted(const HeightField& field, const SamplerState& state, float u, float v,
                    FetchCounts* counts) {
    Sampler<true> sampler(field, state, counts);
    return sampler.Sample(glm::vec2(u, v));
}

}  // namespace reliefsim
