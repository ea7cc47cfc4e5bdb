// Fuzz harness: the image loaders (texture/image_io.h LoadHeightMapFile,
// maps/cone_map.h LoadExternalConeMap) on arbitrary file contents.
//
// Input layout: byte 0 picks the file name's extension (kExtensions, by value modulo its
// size; the last entry is no extension, so OpenImageIO probes every reader), byte 1 the
// options:
//   bit 7 = 0: LoadHeightMapFile, channel = (bits 0-2) % 5 (Auto, R, G, B, A),
//              stores = bit 3 (height, depth);
//   bit 7 = 1: LoadExternalConeMap, channel = (bits 0-2) % 5 - 1 (-1 = all four, 0..3),
//              kind = bit 3 (cone, quad), expected size 4x4 when bit 4 is set.
// The rest is written to a temporary file and loaded. A reliefsim::Error is the normal
// answer to bad input; anything else that escapes (std::bad_alloc, ...) or a crash or
// sanitizer report is a finding.
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "maps/cone_map.h"
#include "texture/image_io.h"

namespace {

constexpr const char* kExtensions[] = {".png", ".tga", ".tif", ".exr",
                                       ".jpg", ".hdr", ".bmp", ""};
constexpr size_t kExtensionCount = sizeof(kExtensions) / sizeof(kExtensions[0]);

/// One file name per process (libFuzzer -fork/-jobs runs several), removed after each
/// input.
std::string TempPath(const char* extension) {
    static const std::string base = [] {
        const char* dir = std::getenv("TMPDIR");
        return std::string(dir && *dir ? dir : "/tmp") + "/rs_fuzz_image_" +
               std::to_string(long(getpid()));
    }();
    return base + extension;
}

bool WriteFile(const std::string& path, const uint8_t* data, size_t size) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return false;
    const bool ok = std::fwrite(data, 1, size, f) == size;
    return std::fclose(f) == 0 && ok;
}

int Init() {
    // One thread: the fuzzer measures one input at a time and reports stay readable.
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 1);
    // The loaders refuse images whose decode would not fit (core/memory.h); tell them
    // about the fuzzer's own allocation limit (-malloc_limit_mb=2048), which the kernel
    // cannot see, so a small file claiming a 16384x16384 image is refused, not decoded
    // into 1 GiB.
    setenv("RELIEFSIM_MEMORY_LIMIT", "512M", 0);
    return 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const int init = Init();
    (void)init;
    if (size < 2) return 0;
    const std::string path = TempPath(kExtensions[data[0] % kExtensionCount]);
    const uint8_t opts = data[1];
    if (!WriteFile(path, data + 2, size - 2)) {
        std::perror(path.c_str());
        std::abort();  // the harness cannot work (disk full, no /tmp): stop loudly
    }
    try {
        if (opts & 0x80) {
            const int channel = int(opts & 7) % 5 - 1;
            const auto kind =
                (opts & 8) ? reliefsim::ConeKind::Quad : reliefsim::ConeKind::Cone;
            const int expect = (opts & 16) ? 4 : 0;
            const reliefsim::ConeMap m =
                reliefsim::LoadExternalConeMap(path, kind, channel, expect, expect);
            if (m.values.size() !=
                size_t(m.width) * size_t(m.height) * size_t(m.channels))
                std::abort();  // the map does not hold what it says
        } else {
            constexpr reliefsim::Channel kChannels[] = {
                reliefsim::Channel::Auto, reliefsim::Channel::R, reliefsim::Channel::G,
                reliefsim::Channel::B, reliefsim::Channel::A};
            reliefsim::MapLoadOptions o;
            o.channel = kChannels[(opts & 7) % 5];
            o.stores = (opts & 8) ? reliefsim::Stores::Depth : reliefsim::Stores::Height;
            const reliefsim::DepthField hf = reliefsim::LoadHeightMapFile(path, o);
            if (hf.depth.size() != size_t(hf.width) * size_t(hf.height)) std::abort();
        }
    } catch (const reliefsim::Error&) {
        // bad input, reported as such: the expected outcome
    }
    std::remove(path.c_str());
    (void)OIIO::geterror();  // drop any message OpenImageIO kept for this thread
    return 0;
}
