// The kernel catalogue (kernels/registry.h).
#include "kernels/registry.h"

#include <charconv>
#include <cmath>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/param_name.h"

namespace reliefsim {

namespace {

std::string FormatNumber(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

template <class... K>
std::vector<const KernelInfo*> InfosOf(KernelList<K...>) {
    return {&K::Info()...};
}

}  // namespace

std::span<const KernelInfo* const> Methods() {
    static const std::vector<const KernelInfo*> kMethods = InfosOf(KernelTypes{});
    return kMethods;
}

const KernelInfo& FindMethod(std::string_view name) {
    for (const KernelInfo* m : Methods())
        if (m->name == name) return *m;
    std::string valid;
    for (const KernelInfo* m : Methods())
        valid += std::string(valid.empty() ? "" : ", ") + std::string(m->name);
    valid += ", " + std::string(kExactMethod);
    if (name == kExactMethod)
        throw Error(ParamName("method") +
                    " exact: the exact reference is not a kernel; only render "
                    "and trace compute it");
    throw Error(ParamName("method") + " \"" + std::string(name) +
                "\": unknown; must be one of: " + valid);
}

ParamValues ResolveParams(const KernelInfo& method,
                          const std::vector<std::string>& settings) {
    ParamValues values;
    for (const auto& p : method.params) values[std::string(p.name)] = p.defaultValue;
    std::map<std::string, std::string> given;  // key -> its setting, for repeats
    for (const auto& s : settings) {
        auto eq = s.find('=');
        if (eq == std::string::npos || eq == 0)
            throw Error(ParamName("set") + " \"" + s + "\": expected key=value");
        std::string key = s.substr(0, eq), text = s.substr(eq + 1);
        if (const auto [it, fresh] = given.emplace(key, s); !fresh)
            throw Error(ParamName("set") + " " + key + ": given twice (" + it->second +
                        ", then " + s + "); give each parameter once");
        const ParamDef* def = nullptr;
        for (const auto& p : method.params)
            if (p.name == key) def = &p;
        if (!def) {
            std::string valid;
            for (const auto& p : method.params)
                valid += std::string(valid.empty() ? "" : ", ") + std::string(p.name);
            throw Error(ParamName("set") + " " + key + ": not a parameter of method \"" +
                        std::string(method.name) + "\"; valid: " + valid);
        }
        double v = 0.0;
        if (!def->choices.empty()) {
            for (size_t c = 0; c < def->choices.size(); ++c)
                if (def->choices[c] == text) v = double(c), text = std::to_string(c);
        }
        auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (!def->choices.empty() &&
            (ec != std::errc() || ptr != text.data() + text.size() || v < 0 ||
             v >= double(def->choices.size()) || v != std::floor(v))) {
            std::string names;
            for (const auto& c : def->choices)
                names += std::string(names.empty() ? "" : ", ") + std::string(c);
            throw Error(ParamName("set") + " " + s.substr(0, eq) + "=" +
                        s.substr(eq + 1) + ": must be one of: " + names);
        }
        if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v))
            throw Error(ParamName("set") + " " + key + "=" + text + ": not a number");
        if (def->integer && v != std::floor(v))
            throw Error(ParamName("set") + " " + key + "=" + text +
                        ": must be an integer");
        if (v < def->minValue || v > def->maxValue)
            throw Error(ParamName("set") + " " + key + "=" + text +
                        ": out of range; valid range [" + FormatNumber(def->minValue) +
                        ", " + FormatNumber(def->maxValue) + "]");
        values[key] = v;
    }
    return values;
}

Kernel MakeKernel(const KernelInfo& method, const ParamValues& values) {
    Kernel k;
    k.index = -1;
    const auto all = Methods();
    for (size_t i = 0; i < all.size(); ++i)
        if (all[i] == &method) k.index = int(i);
    if (k.index < 0)
        throw Error(ParamName("method") + " \"" + std::string(method.name) +
                    "\": not in the catalogue");
    for (const ParamSpec& p : method.params) {
        auto it = values.find(p.name);
        k.values[std::string(p.name)] = it == values.end() ? p.defaultValue : it->second;
    }
    return k;
}

Filter KernelConeFilter(const Kernel& kernel, Filter heightFilter) {
    auto it = kernel.values.find(kConeFilterParam.name);
    const int choice = it == kernel.values.end() ? 0 : int(it->second);
    static_assert(kConeFilterChoices[1] == "bilinear" &&
                  kConeFilterChoices[2] == "nearest" && kConeFilterChoices[3] == "min4");
    switch (choice) {
        case 1:
            return Filter::Bilinear;
        case 2:
            return Filter::Nearest;
        case 3:
            return Filter::Min4;
        default:
            return heightFilter;
    }
}

uint32_t Kernel::Budget() const {
    auto it = values.find("budget");
    return it == values.end() ? 0u : uint32_t(it->second);
}

}  // namespace reliefsim
