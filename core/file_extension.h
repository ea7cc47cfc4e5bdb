// A path's extension, compared without regard to case (".EXR" is ".exr").
#pragma once

#include <cctype>
#include <filesystem>
#include <string>

namespace reliefsim {

/// The extension of `path` with its dot, lower-cased (ASCII): "m.EXR" -> ".exr"; "" when
/// it has none.
inline std::string LowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

}  // namespace reliefsim
