// `reliefsim sweep` and `reliefsim merge` (app/sweep.h).
#include "app/sweep.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "app/render_options.h"
#include "core/error.h"
#include "core/output_set.h"
#include "core/param_name.h"
#include "render/frame.h"
#include "render/outputs.h"
#include "texture/image_io.h"

namespace reliefsim {

namespace fs = std::filesystem;
using ojson = nlohmann::ordered_json;

namespace {

// ---- configuration ------------------------------------------------------------------

/// Most configurations one sweep may hold (a config that crosses more is refused before
/// any work).
constexpr size_t kMaxConfigurations = 1000000;

/// The render keys a view, or the top level, may set.
const std::vector<std::string>& RenderKeys() {
    static const std::vector<std::string> kKeys = {
        "view_angle",       "azimuth",         "distance", "fov",
        "depth_scale",      "tiling",          "filter",   "wrap",
        "texture_format",   "threads",         "lanes",    "camera",
        "view_dir",         "light_dir",       "shadow",   "shadow_steps",
        "shadow_softening", "shadow_penumbra", "ao",       "cone_bounds"};
    return kKeys;
}

std::string Join(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
    return s;
}

[[noreturn]] void Bad(const std::string& where, const std::string& what) {
    throw Error(where + ": " + what);
}

double Number(const ojson& v, const std::string& where) {
    if (!v.is_number()) Bad(where, "expected a number, got " + v.dump());
    return v.get<double>();
}

std::string Text(const ojson& v, const std::string& where) {
    if (!v.is_string()) Bad(where, "expected a string, got " + v.dump());
    return v.get<std::string>();
}

template <class E, size_t N>
E EnumValue(const EnumNames<E, N>& names, const ojson& v, const std::string& where) {
    const std::string s = Text(v, where);
    if (auto e = names.Parse(s)) return *e;
    std::vector<std::string> valid;
    for (const auto& entry : names.Entries()) valid.push_back(std::string(entry.name));
    Bad(where, "\"" + s + "\" is unknown; must be one of: " + Join(valid));
}

/// Applies one render key of a view or of the top level to the settings.
void ApplyRenderKey(RenderSettings& s, const std::string& key, const ojson& v,
                    const std::string& where) {
    const std::string at = where + " \"" + key + "\"";
    if (key == "view_angle")
        s.viewAngle = float(Number(v, at));
    else if (key == "azimuth")
        s.azimuth = float(Number(v, at));
    else if (key == "distance")
        s.distance = float(Number(v, at));
    else if (key == "fov")
        s.fovY = float(Number(v, at));
    else if (key == "depth_scale")
        s.depthScale = float(Number(v, at));
    else if (key == "tiling")
        s.tiling = float(Number(v, at));
    else if (key == "filter")
        s.sampler.filter = EnumValue(kFilterNames, v, at);
    else if (key == "wrap")
        s.sampler.wrap = EnumValue(kWrapModeNames, v, at);
    else if (key == "texture_format")
        s.sampler.precision = EnumValue(kTextureFormatNames, v, at);
    else if (key == "threads" || key == "lanes") {
        const double n = Number(v, at);
        if (!(std::abs(n) <= 1e6) || n != double(int(n)))
            Bad(at, "expected an integer in [-1e6, 1e6], got " + v.dump());
        (key == "threads" ? s.threads : s.lanes) = int(n);
    } else if (key == "camera") {
        s.camera = EnumValue(kCameraNames, v, at);
    } else if (key == "shadow") {
        s.shadow = EnumValue(kShadowNames, v, at);
    } else if (key == "ao") {
        s.ao = EnumValue(kAoNames, v, at);
    } else if (key == "cone_bounds") {
        s.maps.bounds = EnumValue(kConeBoundsNames, v, at);
    } else if (key == "shadow_steps") {
        const double n = Number(v, at);
        if (!(std::abs(n) <= 1e6) || n != double(int(n)))
            Bad(at, "expected an integer in [-1e6, 1e6], got " + v.dump());
        s.shadowSteps = int(n);
    } else if (key == "shadow_softening") {
        s.shadowSoftening = float(Number(v, at));
    } else if (key == "shadow_penumbra") {
        s.shadowPenumbra = float(Number(v, at));
    } else if (key == "view_dir") {
        if (!v.is_array() || v.size() != 3)
            Bad(at, "expected [X, Y, Z], got " + v.dump());
        s.viewDir = glm::vec3(float(Number(v[0], at)), float(Number(v[1], at)),
                              float(Number(v[2], at)));
    } else if (key == "light_dir") {
        if (!v.is_array() || v.size() != 3)
            Bad(at, "expected [X, Y, Z], got " + v.dump());
        s.lightDir = glm::vec3(float(Number(v[0], at)), float(Number(v[1], at)),
                               float(Number(v[2], at)));
    } else {
        Bad(at, "unknown key; valid: " + Join(RenderKeys()));
    }
}

bool IsRenderKey(const std::string& key) {
    const auto& k = RenderKeys();
    return std::find(k.begin(), k.end(), key) != k.end();
}

/// A --set value as text: integers without a decimal point.
std::string SetValueText(double v) {
    char buf[32];
    if (std::abs(v) < 1e15 && v == double(int64_t(v)))
        std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(v));
    else
        std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

struct MapEntry {
    std::string map, channel = "auto", stores = "height";
};

MapEntry ParseMap(const ojson& m, const std::string& where) {
    MapEntry e;
    if (m.is_string()) {
        e.map = m.get<std::string>();
    } else if (m.is_object()) {
        for (const auto& [k, v] : m.items()) {
            if (k == "map")
                e.map = Text(v, where + " \"map\"");
            else if (k == "map_channel") {
                e.channel = Text(v, where + " \"map_channel\"");
                EnumValue(kChannelNames, v, where + " \"map_channel\"");
            } else if (k == "map_stores") {
                e.stores = Text(v, where + " \"map_stores\"");
                EnumValue(kStoresNames, v, where + " \"map_stores\"");
            } else {
                Bad(where + " \"" + k + "\"",
                    "unknown key; valid: map, map_channel, map_stores");
            }
        }
    } else {
        Bad(where, "expected a map name or {\"map\": ...}, got " + m.dump());
    }
    if (e.map.empty()) Bad(where, "no \"map\"");
    return e;
}

/// A value of a method's "set": a number or, for a parameter with named choices
/// (`refine`, `cone_filter`), a name; ResolveParams validates both.
ojson SetValue(const ojson& v, const std::string& where) {
    if (v.is_string()) return v;
    return Number(v, where);
}

/// The crossed values of a method's "set": every combination, the last key fastest.
std::vector<std::vector<std::pair<std::string, ojson>>> CrossSet(
    const ojson& set, const std::string& where) {
    std::vector<std::vector<std::pair<std::string, ojson>>> combos = {{}};
    if (set.is_null()) return combos;
    if (!set.is_object()) Bad(where, "expected an object of key: value or [values]");
    for (const auto& [key, value] : set.items()) {
        const std::string at = where + " \"" + key + "\"";
        std::vector<ojson> values;
        if (value.is_array()) {
            if (value.empty()) Bad(at, "an empty list");
            for (const ojson& x : value) values.push_back(SetValue(x, at));
        } else {
            values.push_back(SetValue(value, at));
        }
        if (combos.size() * values.size() > kMaxConfigurations)
            Bad(at, "the crossed lists give more than " +
                        std::to_string(kMaxConfigurations) + " configurations");
        std::vector<std::vector<std::pair<std::string, ojson>>> next;
        for (const auto& c : combos)
            for (const ojson& x : values) {
                auto d = c;
                d.emplace_back(key, x);
                next.push_back(std::move(d));
            }
        combos = std::move(next);
    }
    return combos;
}

// ---- rows and tables ----------------------------------------------------------------

/// The leaves of a JSON value with their dotted paths, in the value's order.
template <class J>
void Flatten(const J& v, const std::string& path,
             std::vector<std::pair<std::string, std::string>>& out) {
    if (v.is_object()) {
        for (const auto& [k, x] : v.items())
            Flatten(x, path.empty() ? k : path + "." + k, out);
    } else if (v.is_array()) {
        for (size_t i = 0; i < v.size(); ++i)
            Flatten(v[i], path + "." + std::to_string(i), out);
    } else if (v.is_string()) {
        out.emplace_back(path, v.template get<std::string>());
    } else if (v.is_null()) {
        out.emplace_back(path, "");
    } else {
        out.emplace_back(path, v.dump());
    }
}

std::string CsvCell(const std::string& s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string RowFile(const fs::path& dir, int index) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.json", index);
    return (dir / "rows" / name).string();
}

std::string ReadText(const fs::path& path, const std::string& subject) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(subject + " \"" + path.string() + "\": cannot be read");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

/// Every row file under dir/rows, by index.
std::map<int, ojson> ReadRows(const fs::path& dir) {
    std::map<int, ojson> rows;
    std::error_code ec;
    if (!fs::is_directory(dir / "rows", ec)) return rows;
    for (const auto& e : fs::directory_iterator(dir / "rows")) {
        if (e.path().extension() != ".json" || !e.is_regular_file()) continue;
        ojson row;
        try {
            row = ojson::parse(ReadText(e.path(), "sweep row"));
        } catch (const nlohmann::json::exception&) {
            throw Error("sweep row \"" + e.path().string() + "\": not valid JSON");
        }
        if (!row.contains("index") || !row["index"].is_number_integer())
            throw Error("sweep row \"" + e.path().string() + "\": has no index");
        const int index = row["index"].get<int>();
        rows[index] = std::move(row);
    }
    return rows;
}

/// A row without its timing: what must agree between two runs of one configuration.
ojson WithoutTiming(ojson row) {
    if (row.contains("metrics")) row["metrics"].erase("timing");
    return row;
}

std::string CanonicalConfig(const std::string& text) {
    return ojson::parse(text).dump(2) + "\n";
}

void WriteSummaries(const fs::path& dir, const std::map<int, ojson>& byIndex) {
    std::vector<ojson> rows;
    for (const auto& [i, r] : byIndex) rows.push_back(r);
    OutputSet out("sweep --out \"" + dir.string() + "\"");
    out.Add((dir / "results.csv").string());
    out.Add((dir / "tables.md").string());
    out.Write((dir / "results.csv").string(), SweepCsv(rows));
    out.Write((dir / "tables.md").string(), SweepTables(rows));
    out.Commit();
}

/// The checks of render's --out (app/render_options.h CheckOutputDirectory) for a sweep
/// folder: not empty, a folder if it exists, parents that are folders, and no folder in
/// place of a file it writes.
void CheckSweepFolder(const std::string& option, const std::string& dir) {
    CheckOutputDirectory(option, dir,
                         {"sweep.json", "results.csv", "tables.md", "mse_vs_steps.png",
                          "mse_vs_time.png"});
}

void CreateFolder(const fs::path& path, const std::string& option) {
    std::error_code ec;
    fs::create_directories(path, ec);
    if (ec)
        throw Error(option + " \"" + path.parent_path().string() +
                    "\": cannot create its folder (" + ec.message() + ")");
}

void ProgressBar(int done, int total, const std::string& what) {
    const int width = 30, filled = total > 0 ? done * width / total : width;
    std::fprintf(
        stderr, "\r[%s%s] %d/%d %-40.40s", std::string(size_t(filled), '#').c_str(),
        std::string(size_t(width - filled), ' ').c_str(), done, total, what.c_str());
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
}

}  // namespace

std::vector<SweepConfig> ParseSweepConfig(const std::string& text,
                                          const std::string& subject) {
    // A configuration names parameters by their keys ("view_angle"), not by flags.
    const ScopedParamNamer keys(nullptr);
    ojson root;
    try {
        root = ojson::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw Error(subject + ": not valid JSON (" + std::string(e.what()) + ")");
    }
    if (!root.is_object()) Bad(subject, "expected a JSON object");
    RenderSettings base;
    base.width = base.height = 256;
    std::vector<MapEntry> maps;
    std::vector<ojson> views = {ojson::object()};
    const ojson* methods = nullptr;
    for (const auto& [key, v] : root.items()) {
        const std::string at = subject + " \"" + key + "\"";
        if (key == "size") {
            ParseSize(Text(v, at), base.width, base.height);
        } else if (key == "maps") {
            if (!v.is_array() || v.empty()) Bad(at, "expected a non-empty list of maps");
            for (size_t i = 0; i < v.size(); ++i)
                maps.push_back(ParseMap(v[i], at + " [" + std::to_string(i) + "]"));
        } else if (key == "views") {
            if (!v.is_array() || v.empty()) Bad(at, "expected a non-empty list of views");
            views.clear();
            for (const ojson& x : v) {
                if (!x.is_object()) Bad(at, "each view is an object of render keys");
                views.push_back(x);
            }
        } else if (key == "methods") {
            if (!v.is_array() || v.empty())
                Bad(at, "expected a non-empty list of methods");
            methods = &v;
        } else if (IsRenderKey(key)) {
            ApplyRenderKey(base, key, v, subject);
        } else {
            Bad(at,
                "unknown key; valid: size, maps, views, methods, " + Join(RenderKeys()));
        }
    }
    if (maps.empty()) Bad(subject, "no \"maps\"");
    if (!methods) Bad(subject, "no \"methods\"");
    std::vector<SweepConfig> configs;
    for (size_t mi = 0; mi < maps.size(); ++mi)
        for (size_t vi = 0; vi < views.size(); ++vi) {
            RenderSettings viewSettings = base;
            const std::string vat = subject + " \"views\" [" + std::to_string(vi) + "]";
            for (const auto& [k, x] : views[vi].items())
                ApplyRenderKey(viewSettings, k, x, vat);
            // As render refuses them (each would be ignored, yet be a column).
            try {
                RefuseIgnoredSettings(viewSettings, [&](std::string_view k) {
                    return views[vi].contains(k) || root.contains(k);
                });
            } catch (const Error& e) {
                Bad(vat, e.what());
            }
            for (size_t ki = 0; ki < methods->size(); ++ki) {
                const ojson& m = (*methods)[ki];
                const std::string mat =
                    subject + " \"methods\" [" + std::to_string(ki) + "]";
                if (!m.is_object() || !m.contains("method"))
                    Bad(mat, "expected {\"method\": NAME, \"set\": {...}}");
                for (const auto& [k, x] : m.items())
                    if (k != "method" && k != "set")
                        Bad(mat + " \"" + k + "\"", "unknown key; valid: method, set");
                const std::string method = Text(m["method"], mat + " \"method\"");
                for (const auto& combo :
                     CrossSet(m.contains("set") ? m["set"] : ojson(), mat + " \"set\"")) {
                    if (configs.size() >= kMaxConfigurations)
                        Bad(subject,
                            "more than " + std::to_string(kMaxConfigurations) +
                                " configurations (maps x views x methods x sets)");
                    SweepConfig c;
                    c.index = int(configs.size());
                    c.map = maps[mi].map;
                    c.mapChannel = maps[mi].channel;
                    c.mapStores = maps[mi].stores;
                    c.settings = viewSettings;
                    c.settings.method = method;
                    c.columns["index"] = c.index;
                    c.columns["map"] = c.map;
                    c.columns["map_channel"] = c.mapChannel;
                    c.columns["map_stores"] = c.mapStores;
                    c.columns["view"] = int(vi);
                    c.columns["method"] = method;
                    for (const auto& [k, value] : combo) {
                        if (value.is_string()) {
                            const std::string name = value.get<std::string>();
                            c.settings.set.push_back(k + "=" + name);
                            c.columns["set." + k] = name;
                            continue;
                        }
                        const double x = value.get<double>();
                        c.settings.set.push_back(k + "=" + SetValueText(x));
                        if (std::abs(x) < 1e15 && x == double(int64_t(x)))
                            c.columns["set." + k] = int64_t(x);
                        else
                            c.columns["set." + k] = x;
                    }
                    try {
                        ValidateSettings(c.settings);
                    } catch (const Error& e) {
                        Bad(mat + " (configuration " + std::to_string(c.index) + ")",
                            e.what());
                    }
                    configs.push_back(std::move(c));
                }
            }
        }
    return configs;
}

std::string SweepCsv(const std::vector<ojson>& rows) {
    std::vector<std::vector<std::pair<std::string, std::string>>> cells;
    std::vector<std::string> config, metrics, timing;
    std::set<std::string> seen;
    auto add = [&](std::vector<std::string>& cols, const std::string& name) {
        if (seen.insert(name).second) cols.push_back(name);
    };
    for (const ojson& r : rows) {
        std::vector<std::pair<std::string, std::string>> c;
        Flatten(r["columns"], "", c);
        for (const auto& [k, v] : c) add(config, k);
        std::vector<std::pair<std::string, std::string>> m;
        Flatten(r["metrics"], "", m);
        for (const auto& [k, v] : m)
            add(k.rfind("timing.", 0) == 0 ? timing : metrics, k);
        c.insert(c.end(), m.begin(), m.end());
        cells.push_back(std::move(c));
    }
    std::vector<std::string> header = config;
    header.insert(header.end(), metrics.begin(), metrics.end());
    header.insert(header.end(), timing.begin(), timing.end());
    std::string csv;
    for (size_t i = 0; i < header.size(); ++i) csv += (i ? "," : "") + CsvCell(header[i]);
    csv += "\n";
    for (const auto& row : cells) {
        std::map<std::string, std::string> byName(row.begin(), row.end());
        for (size_t i = 0; i < header.size(); ++i) {
            auto it = byName.find(header[i]);
            csv += (i ? "," : "") +
                   (it == byName.end() ? std::string() : CsvCell(it->second));
        }
        csv += "\n";
    }
    return csv;
}

std::string SweepTables(const std::vector<ojson>& rows) {
    std::string md =
        "# Sweep results\n\nOne table per map, view and method, in the "
        "dissertation's layout; MSE is its metric (`mse_paper`), exact MSE and "
        "missed pixels are against the exact reference; time is the frame loop.\n";
    std::string last;
    for (const ojson& r : rows) {
        const ojson& c = r["columns"];
        const ojson& m = r["metrics"];
        const std::string group = c["map"].get<std::string>() + " | view " +
                                  c["view"].dump() + " | " +
                                  c["method"].get<std::string>();
        if (group != last) {
            md += "\n## " + c["method"].get<std::string>() + " on " +
                  c["map"].get<std::string>() + ", view " + c["view"].dump() + "\n\n" +
                  "| steps | avg steps per pixel | MSE | exact MSE | missed pixels | "
                  "time (ms) |\n"
                  "|---|---|---|---|---|---|\n";
            last = group;
        }
        std::string steps;
        for (const auto& [k, v] : c.items())
            if (k.rfind("set.", 0) == 0)
                steps += (steps.empty() ? "" : ", ") + k.substr(4) + "=" +
                         (v.is_string() ? v.get<std::string>() : v.dump());
        char line[256];
        auto num = [&](const char* key) {
            return m.contains(key) && m[key].is_number() ? m[key].get<double>() : 0.0;
        };
        std::snprintf(line, sizeof line, "| %s | %.3f | %.4g | %.4g | %s | %.2f |\n",
                      steps.empty() ? "defaults" : steps.c_str(), num("avg_iterations"),
                      num("mse_paper"), num("mse_exact_depth"),
                      m.contains("missed_geometry_pixels")
                          ? m["missed_geometry_pixels"].dump().c_str()
                          : "",
                      m.contains("timing")
                          ? m["timing"]["frame_seconds"].get<double>() * 1e3
                          : 0.0);
        md += line;
    }
    return md;
}

int RunSweep(const std::string& configText, const std::string& subject,
             const std::string& outDir, const SweepRunOptions& o) {
    if (o.taskCount < 1 || o.taskIndex < 0 || o.taskIndex >= o.taskCount)
        throw Error("--task-index " + std::to_string(o.taskIndex) + " --task-count " +
                    std::to_string(o.taskCount) + ": need 0 <= index < count");
    const std::vector<SweepConfig> configs = ParseSweepConfig(configText, subject);
    CheckSweepFolder("--out", outDir);
    const fs::path dir(outDir);
    std::error_code ec;
    const std::string canonical = CanonicalConfig(configText);
    const fs::path stored = dir / "sweep.json";
    if (fs::exists(stored, ec) && ReadText(stored, "sweep") != canonical)
        throw Error(
            "--out \"" + outDir +
            "\": holds a sweep of another configuration (its sweep.json differs); "
            "use a new folder");
    for (const SweepConfig& c : configs)
        RequireFrameMemory(c.settings.width, c.settings.height);  // one size per sweep
    // Every map is loaded (and so checked) before any row is computed.
    std::map<std::string, DepthField> fields;
    auto key = [](const SweepConfig& c) {
        return c.map + "\n" + c.mapChannel + "\n" + c.mapStores;
    };
    for (const SweepConfig& c : configs) {
        if (c.index % o.taskCount != o.taskIndex || fields.count(key(c))) continue;
        MapLoadOptions lo;
        lo.channel = *ParseChannel(c.mapChannel);
        lo.stores = *ParseStores(c.mapStores);
        fields.emplace(key(c), LoadHeightMap(c.map, lo));
    }
    CreateFolder(dir / "rows", "--out");
    if (!fs::exists(stored, ec)) WriteFileAtomically(stored.string(), canonical, "sweep");
    const std::map<int, ojson> have = ReadRows(dir);
    std::vector<const SweepConfig*> todo;
    int mine = 0;
    for (const SweepConfig& c : configs) {
        if (c.index % o.taskCount != o.taskIndex) continue;
        ++mine;
        if (!have.count(c.index)) todo.push_back(&c);
    }
    int done = mine - int(todo.size()), computed = 0;
    for (const SweepConfig* c : todo) {
        if (o.maxRows >= 0 && computed >= o.maxRows) break;
        if (o.progress) ProgressBar(done, mine, c->settings.method + " on " + c->map);
        const DepthField& field = fields.at(key(*c));
        const RenderOutput out = Render(field, c->settings);
        ojson row;
        row["index"] = c->index;
        row["columns"] = c->columns;
        row["metrics"] = ojson::parse(MetricsJson(out, c->settings, field).dump());
        WriteFileAtomically(RowFile(dir, c->index), row.dump(1) + "\n", "sweep");
        ++done, ++computed;
    }
    if (o.progress && done == mine) ProgressBar(done, mine, "done");
    WriteSummaries(dir, ReadRows(dir));
    return computed;
}

void MergeSweeps(const std::vector<std::string>& partDirs, const std::string& outDir) {
    if (partDirs.empty()) throw Error("merge: give the shard folders to join");
    CheckSweepFolder("merge --out", outDir);
    std::string canonical;
    std::map<int, ojson> rows;
    for (const std::string& part : partDirs) {
        const fs::path p(part);
        const std::string config = ReadText(p / "sweep.json", "merge: shard");
        if (canonical.empty()) canonical = config;
        if (config != canonical)
            throw Error("merge: \"" + part + "\" holds a sweep of another configuration");
        for (auto& [i, r] : ReadRows(p)) {
            auto it = rows.find(i);
            if (it != rows.end() && WithoutTiming(it->second) != WithoutTiming(r))
                throw Error("merge: configuration " + std::to_string(i) +
                            " differs between shards (\"" + part + "\")");
            rows.emplace(i, std::move(r));
        }
    }
    const size_t expected = ParseSweepConfig(canonical, "merge: sweep.json").size();
    for (size_t i = 0; i < expected; ++i)
        if (!rows.count(int(i)))
            throw Error("merge: configuration " + std::to_string(i) + " of " +
                        std::to_string(expected) + " is in none of the shards");
    const fs::path dir(outDir);
    CreateFolder(dir / "rows", "merge --out");
    WriteFileAtomically((dir / "sweep.json").string(), canonical, "merge");
    for (const auto& [i, r] : rows)
        WriteFileAtomically(RowFile(dir, i), r.dump(1) + "\n", "merge");
    WriteSummaries(dir, rows);
}

}  // namespace reliefsim
