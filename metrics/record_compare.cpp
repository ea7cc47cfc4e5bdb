// Bit-level record comparison and the lane-cost check (plain data: no GL, no raster).
#include "metrics/record_compare.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/error.h"

namespace reliefsim {

uint64_t UlpDistance(float a, float b) {
    auto ordered = [](float f) {
        int32_t i;
        std::memcpy(&i, &f, sizeof i);
        // Map the sign-magnitude bit pattern onto a monotonic integer line (-0 just below
        // +0).
        return i >= 0 ? int64_t(i) : -int64_t(i & 0x7fffffff) - 1;
    };
    const int64_t d = ordered(a) - ordered(b);
    return uint64_t(d < 0 ? -d : d);
}

namespace {
bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }
void Finish(FieldAgreement& f, uint64_t pixels) {
    f.fraction = pixels ? double(f.identical) / double(pixels) : 1.0;
}
}  // namespace

RecordComparison CompareRecords(const FrameRecord& cpu, const FrameRecord& gl,
                                int maxListed) {
    if (cpu.width != gl.width || cpu.height != gl.height)
        throw Error("record comparison: sizes differ (" + std::to_string(cpu.width) +
                    "x" + std::to_string(cpu.height) + " vs " + std::to_string(gl.width) +
                    "x" + std::to_string(gl.height) + ")");
    RecordComparison c;
    const size_t n = size_t(cpu.width) * size_t(cpu.height);
    c.diffMap.assign(n, 0.0f);
    c.mask.assign(n, 0);
    for (int y = 0; y < cpu.height; ++y) {
        for (int x = 0; x < cpu.width; ++x) {
            const size_t i = cpu.Index(x, y);
            const bool a = cpu.Covered(i), b = gl.Covered(i);
            if (!a && !b) continue;
            c.mask[i] = 1;
            if (a != b) {
                (a ? c.cpuOnly : c.glOnly) += 1;
                c.diffMap[i] = 5.0f;
                if (int(c.firstDiffs.size()) < maxListed) c.firstDiffs.push_back({x, y});
                continue;
            }
            ++c.pixels;
            int differing = 0;
            const bool uvSame =
                SameBits(cpu.hitU[i], gl.hitU[i]) && SameBits(cpu.hitV[i], gl.hitV[i]);
            c.hitUv.identical += uvSame;
            differing += !uvSame;
            c.hitUv.maxDiff =
                std::max({c.hitUv.maxDiff, UlpDistance(cpu.hitU[i], gl.hitU[i]),
                          UlpDistance(cpu.hitV[i], gl.hitV[i])});
            const bool depthSame = SameBits(cpu.hitDepth[i], gl.hitDepth[i]);
            c.hitDepth.identical += depthSame;
            differing += !depthSame;
            c.hitDepth.maxDiff = std::max(c.hitDepth.maxDiff,
                                          UlpDistance(cpu.hitDepth[i], gl.hitDepth[i]));
            const bool itSame =
                cpu.nCoarse[i] == gl.nCoarse[i] && cpu.nRefine[i] == gl.nRefine[i];
            c.iterations.identical += itSame;
            differing += !itSame;
            const int64_t itA = int64_t(cpu.nCoarse[i]) + cpu.nRefine[i];
            const int64_t itB = int64_t(gl.nCoarse[i]) + gl.nRefine[i];
            c.iterations.maxDiff =
                std::max(c.iterations.maxDiff, uint64_t(std::abs(itA - itB)));
            const bool fetchSame = cpu.nFetches[i] == gl.nFetches[i];
            c.fetches.identical += fetchSame;
            differing += !fetchSame;
            c.fetches.maxDiff = std::max(
                c.fetches.maxDiff,
                uint64_t(std::abs(int64_t(cpu.nFetches[i]) - int64_t(gl.nFetches[i]))));
            const uint8_t flagBits = kFlagBudgetExhausted | kFlagNoHit;
            if ((cpu.flags[i] & flagBits) != (gl.flags[i] & flagBits)) ++c.flagsDiffer;
            c.diffMap[i] = float(differing);
            if (differing > 0 && int(c.firstDiffs.size()) < maxListed)
                c.firstDiffs.push_back({x, y});
        }
    }
    Finish(c.hitUv, c.pixels);
    Finish(c.hitDepth, c.pixels);
    Finish(c.iterations, c.pixels);
    Finish(c.fetches, c.pixels);
    return c;
}

LaneCostCheck CheckLaneCost(const std::vector<uint32_t>& fetches,
                            const std::vector<int16_t>& cpuTriangle, int width,
                            int height, const LaneTrips& lanes,
                            uint64_t summaryLaneFetches) {
    LaneCostCheck c;
    c.summaryLaneFetches = summaryLaneFetches;
    if (fetches.size() != size_t(width) * size_t(height) ||
        cpuTriangle.size() != fetches.size())
        throw Error("lane-cost check: per-pixel fetches (" +
                    std::to_string(fetches.size()) + ") and triangles (" +
                    std::to_string(cpuTriangle.size()) + ") must both hold " +
                    std::to_string(width) + "x" + std::to_string(height) + " pixels");
    const size_t nGroups = lanes.groupTrips.size();
    std::vector<uint32_t> modelTrips(nGroups, 0);
    std::vector<uint8_t> used(nGroups, 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            if (cpuTriangle[i] < 0) continue;
            const size_t key = (size_t(y / 2) * size_t(lanes.blocksX) + size_t(x / 4)) *
                                   size_t(lanes.nTriangles) +
                               size_t(cpuTriangle[i]);
            if (key >= nGroups) throw Error("lane-cost check: group index out of range");
            used[key] = 1;
            modelTrips[key] = std::max(modelTrips[key], fetches[i]);
        }
    for (size_t g = 0; g < nGroups; ++g) {
        c.modelGroups += used[g];
        c.modelLaneFetches += uint64_t(c.lanesPerGroup) * modelTrips[g];
        c.measuredLaneFetches += uint64_t(c.lanesPerGroup) * lanes.groupTrips[g];
        if (modelTrips[g] != lanes.groupTrips[g]) {
            ++c.groupsMismatched;
            if (c.firstMismatches.size() < 10) {
                const int tri = int(g % size_t(lanes.nTriangles));
                const int block = int(g / size_t(lanes.nTriangles));
                c.firstMismatches.push_back({block % lanes.blocksX, block / lanes.blocksX,
                                             tri, modelTrips[g], lanes.groupTrips[g]});
            }
        }
    }
    c.measuredGroups = lanes.groupRuns;
    return c;
}

}  // namespace reliefsim
