// The method registry.
#include "kernels/registry.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace reliefsim {

namespace {

ParamDef LinearSteps(double def) {
    return {"linear_steps", def,  1,
            1024,           true, "linear-search steps over the full depth"};
}
ParamDef RefineSteps(double def, const char* what) {
    return {"refine_steps", def, 0, 64, true, what};
}
const ParamDef kEarlyExit = {
    "early_exit",
    1,
    0,
    1,
    true,
    "1: break out of loops; 0: GPU-style fixed loops (result latched)"};
const ParamDef kBudget = {"budget", 0,    0,
                          1000000,  true, "fetch budget per fragment; 0 = none"};

std::string FormatNumber(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

}  // namespace

const std::vector<MethodInfo>& Methods() {
    static const std::vector<MethodInfo> kMethods = {
        {"linear",
         "linear search (steep parallax mapping)",
         "Burger 2018 (004) Alg. 1; McGuire 2005",
         {LinearSteps(32), kEarlyExit, kBudget},
         {}},
        {"relief",
         "linear search + binary search (relief mapping)",
         "Burger 2018 (004) Alg. 1 + Alg. 2; Policarpo & Oliveira (001)",
         {LinearSteps(32), RefineSteps(6, "binary-search steps"), kEarlyExit, kBudget},
         {}},
        {"secant",
         "linear search + iterated secant",
         "Risser, Shah & Pattanaik 2007 (003) section 3 and listing",
         {LinearSteps(32),
          RefineSteps(10, "secant iterations (at most)"),
          {"secant_tolerance", 0.01, 0, 1, false,
           "stop when |sampled depth - ray depth| <= this"},
          kEarlyExit,
          kBudget},
         {}},
        {"interval",
         "linear search + interval search",
         "Burger 2018 (004) Alg. 1 + Alg. 3; Risser et al. interval mapping",
         {LinearSteps(32), RefineSteps(6, "interval-search steps"), kEarlyExit, kBudget},
         {}},
        {"pom",
         "linear search + one secant step (parallax occlusion mapping)",
         "Tatarchuk 2006, as described in Risser et al. 2007 (003) section 2",
         {LinearSteps(32), kEarlyExit, kBudget},
         {}},
    };
    return kMethods;
}

const MethodInfo& FindMethod(std::string_view name) {
    for (const auto& m : Methods())
        if (m.name == name) return m;
    std::string valid;
    for (const auto& m : Methods())
        valid += std::string(valid.empty() ? "" : ", ") + m.name;
    throw Error("--method \"" + std::string(name) +
                "\": unknown; must be one of: " + valid);
}

ParamValues ResolveParams(const MethodInfo& method,
                          const std::vector<std::string>& settings) {
    ParamValues values;
    for (const auto& p : method.params) values[p.name] = p.defaultValue;
    for (const auto& s : settings) {
        auto eq = s.find('=');
        if (eq == std::string::npos || eq == 0)
            throw Error("--set \"" + s + "\": expected key=value");
        std::string key = s.substr(0, eq), text = s.substr(eq + 1);
        const ParamDef* def = nullptr;
        for (const auto& p : method.params)
            if (p.name == key) def = &p;
        if (!def) {
            std::string valid;
            for (const auto& p : method.params)
                valid += std::string(valid.empty() ? "" : ", ") + p.name;
            throw Error("--set " + key + ": not a parameter of method \"" + method.name +
                        "\"; valid: " + valid);
        }
        double v = 0.0;
        auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
        if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v))
            throw Error("--set " + key + "=" + text + ": not a number");
        if (def->integer && v != std::floor(v))
            throw Error("--set " + key + "=" + text + ": must be an integer");
        if (v < def->minValue || v > def->maxValue)
            throw Error("--set " + key + "=" + text + ": out of range; valid range [" +
                        FormatNumber(def->minValue) + ", " + FormatNumber(def->maxValue) +
                        "]");
        values[key] = v;
    }
    return values;
}

Kernel MakeKernel(const MethodInfo& method, const ParamValues& values) {
    auto get = [&](const char* key, double fallback) {
        auto it = values.find(key);
        return it == values.end() ? fallback : it->second;
    };
    LinearSearchKernel k;
    k.params.linearSteps = int(get("linear_steps", 32));
    k.params.refineSteps = int(get("refine_steps", 0));
    k.params.earlyExit = get("early_exit", 1) != 0.0;
    k.params.budget = uint32_t(get("budget", 0));
    k.params.secantTolerance = float(get("secant_tolerance", 0.01));
    if (method.name == "linear")
        k.params.refinement = Refinement::None;
    else if (method.name == "relief")
        k.params.refinement = Refinement::Binary;
    else if (method.name == "secant")
        k.params.refinement = Refinement::Secant;
    else if (method.name == "interval")
        k.params.refinement = Refinement::Interval;
    else if (method.name == "pom")
        k.params.refinement = Refinement::Pom;
    else
        throw Error("--method \"" + method.name + "\": has no kernel yet");
    return k;
}

}  // namespace reliefsim
