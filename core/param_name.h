// How library errors name a parameter. Libraries name their own parameters (snake_case,
// e.g. "search_steps"); a front end may name them its way instead: the command line
// installs its flags ("--search-steps") at start-up (DESIGN.md, module map).
#pragma once

#include <string>
#include <string_view>

namespace reliefsim {

/// Turns a parameter's name into the name a user gave it.
using ParamNamer = std::string (*)(std::string_view param);

/// Installs how ParamName names parameters (once, at start-up, before any other
/// thread runs); nullptr restores the library's own names.
void SetParamNamer(ParamNamer namer);

/// The parameter `param` as errors name it: the installed namer's name, else `param`.
std::string ParamName(std::string_view param);

/// Installs `namer` for its lifetime and restores the previous one (for a single-threaded
/// stretch, e.g. while a sweep's configuration is validated: its keys are the
/// parameters' own names, not flags).
class ScopedParamNamer {
  public:
    explicit ScopedParamNamer(ParamNamer namer);
    ~ScopedParamNamer();
    ScopedParamNamer(const ScopedParamNamer&) = delete;
    ScopedParamNamer& operator=(const ScopedParamNamer&) = delete;

  private:
    ParamNamer previous_;
};

/// The command line's namer: "--" and the name with '-' for '_' ("--search-steps").
std::string FlagName(std::string_view param);

}  // namespace reliefsim
