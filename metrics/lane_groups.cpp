// Lane groups as images (metrics/lane_groups.h).
#include "metrics/lane_groups.h"

#include <algorithm>
#include <map>
#include <string>

#include "core/error.h"

namespace reliefsim {

LaneGroupMap LaneGroups(const FrameRecord& r, const std::vector<int32_t>& piece,
                        int groupWidth, int groupHeight) {
    const size_t n = size_t(r.width) * size_t(r.height);
    if (groupWidth < 1 || groupHeight < 1)
        throw Error("lane groups: size " + std::to_string(groupWidth) + "x" +
                    std::to_string(groupHeight) + "; expected at least 1x1");
    if (piece.size() != n)
        throw Error("lane groups: " + std::to_string(piece.size()) +
                    " piece entries for " + std::to_string(n) + " pixels");
    struct Group {
        uint32_t maxTrips = 0;
        uint64_t sumTrips = 0;
    };
    // Key: (group index, piece), in image order of the groups.
    std::map<std::pair<size_t, int>, Group> groups;
    const size_t groupsX = size_t((r.width + groupWidth - 1) / groupWidth);
    auto key = [&](int x, int y, size_t i) {
        return std::make_pair(size_t(y / groupHeight) * groupsX + size_t(x / groupWidth),
                              int(piece[i]));
    };
    for (int y = 0; y < r.height; ++y)
        for (int x = 0; x < r.width; ++x) {
            const size_t i = r.Index(x, y);
            if (!r.Covered(i)) continue;
            Group& g = groups[key(x, y, i)];
            g.maxTrips = std::max(g.maxTrips, r.nFetches[i]);
            g.sumTrips += r.nFetches[i];
        }
    const uint64_t lanes = uint64_t(groupWidth) * uint64_t(groupHeight);
    LaneGroupMap m;
    m.trips.assign(n, 0.0f);
    m.utilisation.assign(n, 0.0f);
    for (const auto& [k, g] : groups) m.totalCost += lanes * g.maxTrips;
    for (int y = 0; y < r.height; ++y)
        for (int x = 0; x < r.width; ++x) {
            const size_t i = r.Index(x, y);
            if (!r.Covered(i)) continue;
            const Group& g = groups.at(key(x, y, i));
            m.trips[i] = float(g.maxTrips);
            m.utilisation[i] =
                g.maxTrips == 0 ? 0.0f
                                : float(double(g.sumTrips) / double(lanes * g.maxTrips));
        }
    return m;
}

}  // namespace reliefsim
