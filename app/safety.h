// `reliefsim safety`: the safety profile of the methods (docs/exact.md "Safety profile"):
// for each method and view angle, the share of covered pixels whose hit misses the exact
// first hit (missed geometry), measured rather than argued.
#pragma once

#include <string>
#include <vector>

#include "render/scene.h"
#include "texture/depth_field.h"

namespace reliefsim {

struct SafetyProfile {
    std::vector<std::string> methods;
    std::vector<float> viewAngles;
    /// missedShare[m][a]: missed-geometry pixels / covered pixels of method m at angle a.
    std::vector<std::vector<double>> missedShare;
    std::vector<std::vector<double>> uvErrorMean;  ///< texels, the same layout
};

/// Renders `base` (its map, size, sampler, camera options) with each method (base.set
/// applies to each, which must accept it) at each view angle, with the exact reference.
/// Throws Error for a bad method, parameter or angle.
SafetyProfile ComputeSafetyProfile(const DepthField& field, const RenderSettings& base,
                                   const std::vector<std::string>& methods,
                                   const std::vector<float>& viewAngles);

/// A Markdown table: one row per method, one column per angle, shares in percent.
std::string FormatSafetyProfile(const SafetyProfile& profile);

}  // namespace reliefsim
