// Fuzz harness: the `--set key=value` parser, kernels/registry.h ResolveParams.
//
// Input: lines ('\n'). The first line is the method name (FindMethod), every further line
// one "key=value" setting. A reliefsim::Error is the normal answer to bad input. On
// success every parameter of the method must have a value inside its declared range
// (integers integral), and MakeKernel must accept the values. Anything else is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "fuzz/fuzz_input.h"
#include "kernels/registry.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::vector<std::string> lines = reliefsim::fuzz::SplitLines(data, size);
    if (lines.empty()) return 0;
    const std::string name = lines.front();
    lines.erase(lines.begin());
    try {
        const reliefsim::MethodInfo& method = reliefsim::FindMethod(name);
        const reliefsim::ParamValues values = reliefsim::ResolveParams(method, lines);
        if (values.size() != method.params.size()) std::abort();
        for (const reliefsim::ParamDef& p : method.params) {
            auto it = values.find(p.name);
            if (it == values.end()) std::abort();  // a parameter without a value
            const double v = it->second;
            if (!(v >= p.minValue && v <= p.maxValue))
                std::abort();  // out of range (or NaN)
            if (p.integer && v != std::floor(v)) std::abort();
        }
        (void)reliefsim::MakeKernel(method, values);
    } catch (const reliefsim::Error&) {
        // unknown method, unknown key, not a number, out of range: the expected outcome
    }
    return 0;
}
