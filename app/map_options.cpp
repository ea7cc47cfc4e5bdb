// The shared --map options.
#include "app/commands.h"
#include "core/error.h"
#include "texture/image_io.h"

namespace reliefsim {

void AddMapOptions(CLI::App* cmd, MapOptions& o) {
    cmd->add_option(
           "--map", o.map,
           "height map: an image file (PNG, TGA, EXR, TIFF; 8/16-bit or float) or "
           "builtin:NAME[:SIZE] with NAME one of shapes, bumps, steps, noise, flat, "
           "ramp, step")
        ->capture_default_str();
    o.channelOption =
        cmd->add_option("--map-channel", o.channel,
                        "channel holding the height: R|G|B|A (default: grey, else A)")
            ->capture_default_str();
    o.storesOption =
        cmd->add_option("--map-stores", o.stores,
                        "what the file stores: height (white = top) or depth")
            ->capture_default_str();
}

HeightField LoadMapFromOptions(const MapOptions& o) {
    MapLoadOptions lo;
    auto channel = ParseChannel(o.channel);
    if (!channel)
        throw Error("--map-channel \"" + o.channel +
                    "\": must be one of R, G, B, A, auto");
    auto stores = ParseStores(o.stores);
    if (!stores)
        throw Error("--map-stores \"" + o.stores + "\": must be height or depth");
    const bool builtin = o.map.rfind("builtin:", 0) == 0;
    if (builtin && o.channelOption && o.channelOption->count() > 0)
        throw Error("--map-channel " + o.channel +
                    ": applies to image files, not to --map " + o.map +
                    " (a builtin map has one channel)");
    if (builtin && o.storesOption && o.storesOption->count() > 0)
        throw Error("--map-stores " + o.stores +
                    ": applies to image files, not to --map " + o.map +
                    " (a builtin map holds depths already)");
    lo.channel = *channel;
    lo.stores = *stores;
    return LoadHeightMap(o.map, lo);
}

}  // namespace reliefsim
