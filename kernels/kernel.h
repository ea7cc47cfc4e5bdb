// The kernel interface: what a fragment hands to an intersection kernel and gets back.
#pragma once

#include <concepts>
#include <cstdint>
#include <glm/vec2.hpp>

namespace reliefsim {

/// A fragment's view ray in texture space (DESIGN.md conventions): it enters the relief
/// at (uvEntry, depth 0) and p(t) = (uvEntry + t * dirUv, t), so t is the ray's depth and
/// t = 1 reaches the bottom of the relief.
struct MarchInput {
    glm::vec2 uvEntry;  ///< uv where the ray enters the relief (tiling included)
    glm::vec2
        dirUv;  ///< uv travelled per unit depth: -view.xy / view.z * depthScale * tiling
};

/// What a kernel returns for one fragment. Iterations are loop trips; fetches are counted
/// by the sampler the kernel was given.
struct MarchResult {
    glm::vec2 uvHit{0.0f};  ///< uv of the returned point (unwrapped)
    float depthHit = 0.0f;  ///< ray depth t of the returned point, in [0,1]
    uint16_t nCoarse = 0;   ///< coarse-search iterations (linear / cone steps)
    uint16_t nRefine = 0;   ///< refinement iterations (binary / secant / interval)
    bool hit = false;       ///< the coarse search found the ray below the surface
    bool budgetExhausted =
        false;  ///< stopped by the fetch budget; the point is the estimate then
};

/// What a kernel needs of a height sampler: one Sample(uv) returning depth in [0,1]. Both
/// instantiations of texture/sampler.h's Sampler (counted and uncounted) satisfy it.
template <typename S>
concept HeightSampler = requires(S s, glm::vec2 uv) {
    { s.Sample(uv) } -> std::convertible_to<float>;
};

/// Counts a kernel's fetches against its budget (0 = none). Kept inside the kernel so
/// that the uncounted benchmark sampler honours budgets too.
class FetchBudget {
  public:
    explicit FetchBudget(uint32_t budget) : budget_(budget) {}
    /// True when one more fetch is allowed; then it is charged.
    bool Take() {
        if (budget_ != 0 && used_ >= budget_) {
            exhausted_ = true;
            return false;
        }
        ++used_;
        return true;
    }
    bool Exhausted() const { return exhausted_; }
    uint32_t Used() const { return used_; }

  private:
    uint32_t budget_;
    uint32_t used_ = 0;
    bool exhausted_ = false;
};

}  // namespace reliefsim
