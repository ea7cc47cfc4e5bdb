// How library errors name a parameter (core/param_name.h).
#include "core/param_name.h"

#include <atomic>

namespace reliefsim {

namespace {
std::atomic<ParamNamer> gNamer{nullptr};
}  // namespace

void SetParamNamer(ParamNamer namer) { gNamer.store(namer, std::memory_order_release); }

std::string ParamName(std::string_view param) {
    const ParamNamer namer = gNamer.load(std::memory_order_acquire);
    return namer ? namer(param) : std::string(param);
}

ScopedParamNamer::ScopedParamNamer(ParamNamer namer)
    : previous_(gNamer.exchange(namer, std::memory_order_acq_rel)) {}

ScopedParamNamer::~ScopedParamNamer() {
    gNamer.store(previous_, std::memory_order_release);
}

std::string FlagName(std::string_view param) {
    std::string flag = "--";
    for (char c : param) flag += c == '_' ? '-' : c;
    return flag;
}

}  // namespace reliefsim
