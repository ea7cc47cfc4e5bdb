// The light-ray kernels' settings (kernels/shadow.h has the kernels and their equations),
// apart so that the scene's settings need not include the lane sampler.
#pragma once

#include <array>

#include "core/enum_names.h"

namespace reliefsim {

/// The light-ray kernels, in the order of the twin's uShadow values.
enum class ShadowKind { None, Hard, Soft, Cone };

inline constexpr auto kShadowNames = MakeEnumNames<ShadowKind>({
    {"none", ShadowKind::None},
    {"hard", ShadowKind::Hard},
    {"soft", ShadowKind::Soft},
    {"cone", ShadowKind::Cone},
});

/// Ambient occlusion of the hit (render --ao): none, or from the cone map at the hit
/// (dissertation 004 §4.5; kernels/shadow.h AmbientOcclusion).
enum class AoKind { None, Cone };

inline constexpr auto kAoNames = MakeEnumNames<AoKind>({
    {"none", AoKind::None},
    {"cone", AoKind::Cone},
});

inline constexpr int kMaxShadowSteps = 1024;
inline constexpr float kMaxShadowSoftening = 1000.0f;
inline constexpr float kMaxShadowPenumbra = 1000.0f;

/// What the light ray of every lane needs (in float, as the twin's uniforms).
struct ShadowJob {
    ShadowKind kind = ShadowKind::None;
    int steps = 16;              ///< hard: steps from the surface to the top
    float stepInv = 1.0f / 16;   ///< 1.0f / steps, computed once (uShadowStepInv)
    float softening = 0.58f;     ///< soft: Tatarchuk's shadow softening (the SDK's 0.58)
    float penumbra = 8.0f;       ///< cone: the distance-field penumbra factor k (Quilez)
    float rayLength = 1.0f;      ///< cone: |(lu, lv, 1)|, the ray's length per unit rise
    float lu = 0.0f, lv = 0.0f;  ///< uv per unit of rise along the light ray
    /// Ambient occlusion from the kernel's cone map at the hit (its ratio r for csm, the
    /// cone normal's n_z for cns: aoFromNz).
    AoKind ao = AoKind::None;
    bool aoFromNz = false;
    /// Whether any light-ray kernel runs (shadows or AO): the frame then counts their
    /// fetches apart (shadow_fetches) and keeps the visibility.
    bool Any() const { return kind != ShadowKind::None || ao != AoKind::None; }
};

/// Tatarchuk's soft-shadow samples: fractions of the light vector, and their weights.
inline constexpr std::array<float, 7> kSoftShadowFraction = {0.88f, 0.77f, 0.66f, 0.55f,
                                                             0.44f, 0.33f, 0.22f};
inline constexpr std::array<float, 7> kSoftShadowWeight = {1.0f, 2.0f,  4.0f, 6.0f,
                                                           8.0f, 10.0f, 12.0f};

}  // namespace reliefsim
