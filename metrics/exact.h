// The exact reference (method `exact`): the first point of a view ray inside the depth
// surface that bilinear filtering defines, found analytically.
//
// The surface is the bilinear interpolation between texel centres with the sampler's wrap
// mode: texel (i, j) holds its depth at x = i + 0.5, y = j + 0.5 (x = u W, y = v H), and
// over the cell between four neighbouring centres the depth is bilinear in (x, y). Along
// a ray p(t) = (uvEntry + t dirUv, t) (DESIGN.md conventions) both cell coordinates are
// linear in t, so inside one cell "ray depth minus surface depth", g(t), is a quadratic
// in t, and the first hit is the smallest t with g(t) >= 0: the entry point when it is
// already inside, else the first root of the quadratic in the cell. The walk visits the
// cells that the ray's projection crosses, in order, and skips whole blocks of cells
// that a pyramid of block minima proves the ray passes above (t < the block's least
// depth all the way through the block). Everything is computed in double precision.
// docs/exact.md gives the derivation and the validation.
#pragma once

#include <cstdint>
#include <vector>

#include "texture/depth_field.h"
#include "texture/sampler.h"

namespace reliefsim {

/// The first hit of one ray.
struct ExactHit {
    double t = 1.0;            ///< ray depth of the first point inside, in [0, 1]
    double u = 0, v = 0;       ///< uvEntry + t dirUv (unwrapped, tiling included)
    uint32_t cellsTested = 0;  ///< bilinear cells whose quadratic was set up
};

/// A depth field prepared for exact ray queries: the bilinear surface with a wrap mode,
/// and the pyramid of cell minima. Immutable after construction, so one
/// surface serves any number of threads.
class ExactSurface {
  public:
    /// Throws Error (ValidateDepthField) when the field is empty or holds depths outside
    /// [0, 1] or NaN: every ray then meets the surface by t = 1.
    ExactSurface(const DepthField& field, WrapMode wrap);

    /// The first t in [0, 1] with t >= depth(uvEntry + t dirUv) on the bilinear surface.
    ExactHit FirstHit(double u0, double v0, double du, double dv) const;

    /// Whether the ray is outside the surface (t < depth - tolerance) somewhere in
    /// (ta, tb): between a first hit at ta and a later point tb, it left the relief and
    /// came back, so tb lies beyond a structure, not inside the one hit first.
    bool LeavesBetween(double u0, double v0, double du, double dv, double ta, double tb,
                       double tolerance) const;

    /// The bilinear surface's depth at (u, v), in double: what FirstHit solves against
    /// (the dense oracle of the tests samples it).
    double DepthAt(double u, double v) const;

    int Width() const { return width_; }
    int Height() const { return height_; }
    /// Levels of block minima above the cells. Repeat: while both sides are even (0 for
    /// an odd side: every cell the ray crosses is visited); clamp: up to blocks of 256
    /// cells, for any size.
    int PyramidLevels() const { return int(levels_.size()) - 1; }

  private:
    struct Ray;
    struct Cell;
    double Texel(int64_t i, int64_t j) const;
    Cell CellAt(int64_t i, int64_t j) const;
    float BlockMinimum(int level, int64_t bx, int64_t by) const;
    Ray MakeRay(double u0, double v0, double du, double dv) const;
    template <class Visit>
    static bool CrossBlocks(const Ray& ray, int level, double ta, double tb, int64_t bx,
                            int64_t by, Visit&& visit);
    bool Walk(const Ray& ray, int level, double ta, double tb, int64_t bx, int64_t by,
              ExactHit& hit) const;
    bool SolveCell(const Ray& ray, int64_t i, int64_t j, double t0, double t1,
                   ExactHit& hit) const;

    struct Level {
        int width, height;          ///< in blocks
        std::vector<float> minima;  ///< row-major: the least depth of each block's cells
    };

    int width_ = 0, height_ = 0;
    WrapMode wrap_ = WrapMode::Repeat;
    int offset_ = 0;  ///< walk cell i is the surface's cell i - offset_ (clamp: 1)
    std::vector<double> depth_;  ///< the field's depths, row-major
    /// levels_[l]: blocks of 2^l x 2^l walk cells (level 0: the cells; a cell spans the
    /// texel centres i..i+1, j..j+1).
    std::vector<Level> levels_;
};

}  // namespace reliefsim
