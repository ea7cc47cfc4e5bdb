// The shared --map options.
#include "app/commands.h"
#include "app/enum_option.h"
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
    o.channelOption = AddEnumOption(
        cmd, "--map-channel", o.channel, kChannelNames,
        "channel holding the height (auto: the grey channel of a grey image, else A)");
    o.storesOption = AddEnumOption(cmd, "--map-stores", o.stores, kStoresNames,
                                   "what the file stores: height (white = top) or depth");
}

DepthField LoadMapFromOptions(const MapOptions& o) {
    const bool builtin = o.map.rfind("builtin:", 0) == 0;
    if (builtin && o.channelOption && o.channelOption->count() > 0)
        throw Error("--map-channel " + std::string(ToString(o.channel)) +
                    ": applies to image files, not to --map " + o.map +
                    " (a builtin map has one channel)");
    if (builtin && o.storesOption && o.storesOption->count() > 0)
        throw Error("--map-stores " + std::string(ToString(o.stores)) +
                    ": applies to image files, not to --map " + o.map +
                    " (a builtin map holds depths already)");
    MapLoadOptions lo;
    lo.channel = o.channel;
    lo.stores = o.stores;
    return LoadHeightMap(o.map, lo);
}

}  // namespace reliefsim
