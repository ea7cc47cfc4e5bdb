// Perspective-correct attribute interpolation with a fixed float evaluation order.
#pragma once

#include <glm/glm.hpp>

namespace reliefsim {

/// Perspective-correct weights of the three vertices at a pixel.
/// screenBary: window-space (linear) barycentrics of vertices (0,1,2) at the pixel
/// centre; invW: 1 / clip w of each vertex. The order is fixed so results are
/// bit-reproducible:
///     p_k = screenBary[k] * invW[k];  s = (p_0 + p_1) + p_2;  weight_k = p_k * (1 / s).
/// Interpolating attribute/w and 1/w and dividing is the same formula, factored.
inline glm::vec3 PerspectiveWeights(const glm::vec3& screenBary, const glm::vec3& invW) {
    const float p0 = screenBary.x * invW.x;
    const float p1 = screenBary.y * invW.y;
    const float p2 = screenBary.z * invW.z;
    const float invSum = 1.0f / ((p0 + p1) + p2);
    return glm::vec3(p0 * invSum, p1 * invSum, p2 * invSum);
}

/// (a0 * w.x + a1 * w.y) + a2 * w.z, component-wise in exactly that order (no FMA: the
/// build uses -ffp-contract=off). T is float or a glm vector.
template <class T>
inline T Interpolate(const glm::vec3& w, const T& a0, const T& a1, const T& a2) {
    return (a0 * w.x + a1 * w.y) + a2 * w.z;
}

}  // namespace reliefsim
