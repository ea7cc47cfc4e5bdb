// The exact reference: see metrics/exact.h and docs/exact.md.
#include "metrics/exact.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/wrap.h"

namespace reliefsim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int64_t FloorDiv(int64_t a, int64_t b) {  // floor(a / b), b > 0
    const int64_t q = a / b;
    return (a % b != 0 && a < 0) ? q - 1 : q;
}

/// A cell coordinate as an integer, for any double the walk produces (rays are bounded,
/// so this only guards against an Inf reaching a conversion).
int64_t FloorIndex(double x) {
    constexpr double kLimit = 9.0e15;
    return int64_t(std::floor(std::clamp(x, -kLimit, kLimit)));
}

}  // namespace

/// The ray in the walk's cell coordinates X = u W - 0.5 + offset_, Y likewise (texel
/// centres at integers, walk cell (i, j) is [i, i+1) x [j, j+1), the surface's cell
/// (i - offset_, j - offset_)): X(t) = x0 + t dx.
struct ExactSurface::Ray {
    double x0, y0, dx, dy;
    double X(double t) const { return x0 + t * dx; }
    double Y(double t) const { return y0 + t * dy; }
};

/// The four corner depths of a cell.
struct ExactSurface::Cell {
    double d00, d10, d01, d11;
};

namespace {

/// g(s) = g0 + g1 s + g2 s^2: ray depth minus the bilinear depth of cell `c` (walk cell
/// (i, j)) along the ray from t0, s = t - t0. With the cell's local coordinates
/// fx = px + s dx, fy = py + s dy (px, py at t0), D = a + b fx + c fy + e fx fy (a = d00,
/// b = d10 - d00, c = d01 - d00, e = d00 - d10 - d01 + d11), so g0 = t0 - D(t0),
/// g1 = 1 - (b dx + c dy + e (px dy + py dx)), g2 = -e dx dy.
struct CellQuadratic {
    double g0, g1, g2;
    double At(double s) const { return g0 + (g1 + g2 * s) * s; }
};

template <class Ray, class Cell>
CellQuadratic QuadraticInCell(const Ray& ray, const Cell& c, int64_t i, int64_t j,
                              double t0) {
    const double px = ray.X(t0) - double(i), py = ray.Y(t0) - double(j);
    const double a = c.d00, b = c.d10 - c.d00, cc = c.d01 - c.d00,
                 e = (c.d00 - c.d10) - (c.d01 - c.d11);
    return {t0 - (a + b * px + cc * py + e * px * py),
            1.0 - (b * ray.dx + cc * ray.dy + e * (px * ray.dy + py * ray.dx)),
            -e * ray.dx * ray.dy};
}

}  // namespace

ExactSurface::ExactSurface(const DepthField& field, WrapMode wrap)
    : width_(field.width), height_(field.height), wrap_(wrap) {
    ValidateDepthField(field);
    depth_.assign(field.depth.begin(), field.depth.end());
    // Level 0: each cell's least corner; level l + 1: the least of 2 x 2 blocks of level
    // l. Repeat: the W x H cells of one period, halved while both sides stay even (so no
    // block straddles the texture's edge). Clamp: the cells -1 .. W-1 (-1 .. H-1), the
    // only distinct ones (cell i <= -1 equals cell -1, i >= W-1 equals W-1), stored from
    // index 0 (offset_ = 1) and padded with copies of the last to a multiple of the top
    // block size, at most 256 cells; a block past the edges takes the edge block's
    // minimum, which covers the same (repeated) cells.
    int w = width_, h = height_, levels = 0;
    if (wrap == WrapMode::Repeat) {
        while (((w >> levels) % 2 == 0) && ((h >> levels) % 2 == 0)) ++levels;
    } else {
        offset_ = 1;
        const int cells = std::max(width_, height_) + 1;
        while ((1 << (levels + 1)) <= 256 && (1 << levels) < cells) ++levels;
        const int top = 1 << levels;
        w = (width_ + 1 + top - 1) / top * top;
        h = (height_ + 1 + top - 1) / top * top;
    }
    Level cells{w, h, std::vector<float>(size_t(w) * size_t(h))};
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const Cell c = CellAt(i - offset_, j - offset_);
            cells.minima[size_t(j) * size_t(w) + size_t(i)] =
                float(std::min({c.d00, c.d10, c.d01, c.d11}));
        }
    levels_.push_back(std::move(cells));
    for (int l = 0; l < levels; ++l) {
        const Level& below = levels_.back();
        Level up{below.width / 2, below.height / 2, {}};
        up.minima.resize(size_t(up.width) * size_t(up.height));
        for (int j = 0; j < up.height; ++j)
            for (int i = 0; i < up.width; ++i) {
                const size_t c = size_t(2 * j) * size_t(below.width) + size_t(2 * i);
                const size_t w2 = size_t(below.width);
                up.minima[size_t(j) * size_t(up.width) + size_t(i)] =
                    std::min({below.minima[c], below.minima[c + 1], below.minima[c + w2],
                              below.minima[c + w2 + 1]});
            }
        levels_.push_back(std::move(up));
    }
}

double ExactSurface::Texel(int64_t i, int64_t j) const {
    if (wrap_ == WrapMode::Repeat) {
        i = Wrap<int64_t>(i, width_);
        j = Wrap<int64_t>(j, height_);
    } else {
        i = std::clamp<int64_t>(i, 0, width_ - 1);
        j = std::clamp<int64_t>(j, 0, height_ - 1);
    }
    return depth_[size_t(j) * size_t(width_) + size_t(i)];
}

ExactSurface::Cell ExactSurface::CellAt(int64_t i, int64_t j) const {
    return {Texel(i, j), Texel(i + 1, j), Texel(i, j + 1), Texel(i + 1, j + 1)};
}

double ExactSurface::DepthAt(double u, double v) const {
    const double x = u * width_ - 0.5, y = v * height_ - 0.5;
    const int64_t i = FloorIndex(x), j = FloorIndex(y);
    const double fx = x - double(i), fy = y - double(j);
    const Cell c = CellAt(i, j);
    return (c.d00 * (1 - fx) + c.d10 * fx) * (1 - fy) +
           (c.d01 * (1 - fx) + c.d11 * fx) * fy;
}

float ExactSurface::BlockMinimum(int level, int64_t bx, int64_t by) const {
    const Level& l = levels_[size_t(level)];
    if (wrap_ == WrapMode::Repeat) {
        bx = Wrap<int64_t>(bx, l.width);
        by = Wrap<int64_t>(by, l.height);
    } else {
        bx = std::clamp<int64_t>(bx, 0, l.width - 1);
        by = std::clamp<int64_t>(by, 0, l.height - 1);
    }
    return l.minima[size_t(by * l.width + bx)];
}

// Cell (i, j) for t in [t0, t1]: the first root of its quadratic (QuadraticInCell).
bool ExactSurface::SolveCell(const Ray& ray, int64_t i, int64_t j, double t0, double t1,
                             ExactHit& hit) const {
    const Cell c = CellAt(i - offset_, j - offset_);
    if (t1 < std::min({c.d00, c.d10, c.d01, c.d11})) return false;  // above the cell
    ++hit.cellsTested;
    const CellQuadratic quad = QuadraticInCell(ray, c, i, j, t0);
    const double g0 = quad.g0, g1 = quad.g1, g2 = quad.g2;
    if (g0 >= 0) {
        hit.t = t0;
        return true;
    }
    const double len = t1 - t0;
    double s = kInf;
    if (g2 == 0.0) {
        if (g1 > 0.0) s = -g0 / g1;
    } else {
        const double disc = g1 * g1 - 4.0 * g2 * g0;
        if (disc >= 0.0) {
            // The two roots without cancellation: q / g2 and g0 / q.
            const double q = -0.5 * (g1 + std::copysign(std::sqrt(disc), g1));
            const double r1 = q / g2, r2 = g0 / q;
            // g(0) < 0, so the least positive root is where the ray first reaches the
            // surface.
            if (r1 > 0.0) s = r1;
            if (r2 > 0.0) s = std::min(s, r2);
        }
    }
    if (!(s <= len)) return false;
    hit.t = t0 + s;
    return true;
}

// Calls visit(bx, by, t0, t1) for the blocks of 2^level cells that the ray crosses for
// t in [ta, tb], from block (bx, by), in order, until visit returns true (then returns
// true). Block boundaries are recomputed from their index at each step (no accumulated
// increments), and an interval that rounding makes negative is empty.
template <class Visit>
bool ExactSurface::CrossBlocks(const Ray& ray, int level, double ta, double tb,
                               int64_t bx, int64_t by, Visit&& visit) {
    const double size = double(int64_t(1) << level);
    const int stepX = ray.dx > 0 ? 1 : (ray.dx < 0 ? -1 : 0);
    const int stepY = ray.dy > 0 ? 1 : (ray.dy < 0 ? -1 : 0);
    auto nextX = [&](int64_t b) {
        if (stepX == 0) return kInf;
        return (double(stepX > 0 ? b + 1 : b) * size - ray.x0) / ray.dx;
    };
    auto nextY = [&](int64_t b) {
        if (stepY == 0) return kInf;
        return (double(stepY > 0 ? b + 1 : b) * size - ray.y0) / ray.dy;
    };
    double t0 = ta, tx = nextX(bx), ty = nextY(by);
    for (;;) {
        const double t1 = std::max(t0, std::min({tx, ty, tb}));
        if (visit(bx, by, t0, t1)) return true;
        if (t1 >= tb) return false;
        if (tx <= ty) {
            bx += stepX;
            tx = nextX(bx);
        } else {
            by += stepY;
            ty = nextY(by);
        }
        t0 = t1;
    }
}

// The hit walk: cells at level 0; a block the ray may hit (its minimum is not above the
// ray's exit depth) is walked one level down, from the child holding the ray at t0.
bool ExactSurface::Walk(const Ray& ray, int level, double ta, double tb, int64_t bx,
                        int64_t by, ExactHit& hit) const {
    return CrossBlocks(
        ray, level, ta, tb, bx, by, [&](int64_t x, int64_t y, double t0, double t1) {
            if (level == 0) return SolveCell(ray, x, y, t0, t1, hit);
            if (t1 < double(BlockMinimum(level, x, y))) return false;
            const double half = double(int64_t(1) << (level - 1));
            const int64_t cx = std::clamp(FloorIndex(ray.X(t0) / half), 2 * x, 2 * x + 1);
            const int64_t cy = std::clamp(FloorIndex(ray.Y(t0) / half), 2 * y, 2 * y + 1);
            return Walk(ray, level - 1, t0, t1, cx, cy, hit);
        });
}

ExactSurface::Ray ExactSurface::MakeRay(double u0, double v0, double du,
                                        double dv) const {
    RS_CHECK(std::isfinite(u0) && std::isfinite(v0) && std::isfinite(du) &&
             std::isfinite(dv));
    return {u0 * width_ - 0.5 + offset_, v0 * height_ - 0.5 + offset_, du * width_,
            dv * height_};
}

bool ExactSurface::LeavesBetween(double u0, double v0, double du, double dv, double ta,
                                 double tb, double tolerance) const {
    if (!(tb > ta)) return false;
    const Ray ray = MakeRay(u0, v0, du, dv);
    return CrossBlocks(ray, 0, ta, tb, FloorIndex(ray.X(ta)), FloorIndex(ray.Y(ta)),
                       [&](int64_t i, int64_t j, double t0, double t1) {
                           // g on [0, t1 - t0]: its least value is at an end or, for g2 >
                           // 0, at the vertex.
                           const Cell c = CellAt(i - offset_, j - offset_);
                           if (t0 >= std::max({c.d00, c.d10, c.d01, c.d11}) - tolerance)
                               return false;
                           const CellQuadratic g = QuadraticInCell(ray, c, i, j, t0);
                           const double len = t1 - t0;
                           double least = std::min(g.At(0.0), g.At(len));
                           if (g.g2 > 0.0) {
                               const double vertex = -g.g1 / (2.0 * g.g2);
                               if (vertex > 0.0 && vertex < len)
                                   least = std::min(least, g.At(vertex));
                           }
                           return least < -tolerance;
                       });
}

ExactHit ExactSurface::FirstHit(double u0, double v0, double du, double dv) const {
    const Ray ray = MakeRay(u0, v0, du, dv);
    ExactHit hit;
    const int top = PyramidLevels();
    const int64_t size = int64_t(1) << top;
    const int64_t bx = FloorDiv(FloorIndex(ray.x0), size);
    const int64_t by = FloorDiv(FloorIndex(ray.y0), size);
    if (!Walk(ray, top, 0.0, 1.0, bx, by, hit)) {
        // Depths are at most 1, so the ray is inside at t = 1; the walk misses that only
        // when the root at the very bottom rounds past t = 1.
        hit.t = 1.0;
    }
    hit.u = u0 + hit.t * du;
    hit.v = v0 + hit.t * dv;
    return hit;
}

}  // namespace reliefsim
