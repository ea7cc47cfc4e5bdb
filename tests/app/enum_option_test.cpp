// Enumerated options: every name table round-trips, --help lists its names, and a bad
// value is one error line naming the option, the value and the valid names.
#include "app/enum_option.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "maps/cone_map.h"
#include "tests/app/cli_util.h"
#include "texture/image_io.h"
#include "texture/sampler.h"

namespace fs = std::filesystem;
using namespace reliefsim;
using reliefsim::testing::CountLines;
using reliefsim::testing::RunCli;

namespace {

fs::path Scratch() { return reliefsim::testing::Scratch("rs_enum_"); }

/// name -> value -> name and value -> name -> value for every entry, through the table
/// and through the library's Parse*/ToString pair.
template <typename E, size_t N, typename ParseFn, typename NameFn>
void ExpectRoundTrip(const EnumNames<E, N>& names, ParseFn parse, NameFn name) {
    for (const EnumName<E>& e : names.Entries()) {
        const std::optional<E> v = parse(e.name);
        ASSERT_TRUE(v.has_value()) << e.name;
        EXPECT_EQ(*v, e.value) << e.name;
        EXPECT_EQ(name(*v), e.name);
        EXPECT_EQ(names.Parse(names.Name(e.value)), e.value) << e.name;
    }
    EXPECT_FALSE(parse("frob").has_value());
}

/// One option, the command that has it and the names --help must list.
struct EnumOptionCase {
    std::string command;  ///< e.g. "render --size 8x8"
    std::string flag;
    std::vector<std::string> names;
};

template <typename E, size_t N>
std::vector<std::string> Names(const EnumNames<E, N>& table) {
    std::vector<std::string> r;
    for (const EnumName<E>& e : table.Entries()) r.emplace_back(e.name);
    return r;
}

std::vector<EnumOptionCase> Cases() {
    const std::string render = "render --size 8x8";
    const std::string maps = "maps --map builtin:shapes:16";
    return {
        {render, "--filter", Names(kFilterNames)},
        {render, "--wrap", Names(kWrapModeNames)},
        {render, "--texture-format", Names(kTextureFormatNames)},
        {render, "--map-channel", Names(kChannelNames)},
        {render, "--map-stores", Names(kStoresNames)},
        {"trace --pixel 1,1", "--filter", Names(kFilterNames)},
        {maps, "--map-channel", Names(kChannelNames)},
        {maps, "--kind", Names(kConeKindNames)},
        {maps, "--encoding", Names(kConeEncodingNames)},
        {maps, "--external-channel", {"R", "G", "B", "A", "all"}},
    };
}

std::string Join(const std::vector<std::string>& names) {
    std::string r;
    for (const std::string& n : names) r += (r.empty() ? "" : "|") + n;
    return r;
}

}  // namespace

TEST(EnumOption, EveryTableRoundTrips) {
    ExpectRoundTrip(kFilterNames, ParseFilter, [](Filter v) { return ToString(v); });
    ExpectRoundTrip(kWrapModeNames, ParseWrapMode,
                    [](WrapMode v) { return ToString(v); });
    ExpectRoundTrip(kPrecisionNames, ParsePrecision,
                    [](Precision v) { return ToString(v); });
    ExpectRoundTrip(
        kTextureFormatNames,
        [](std::string_view s) { return kTextureFormatNames.Parse(s); },
        [](Precision v) { return kTextureFormatNames.Name(v); });
    ExpectRoundTrip(kChannelNames, ParseChannel, [](Channel v) { return ToString(v); });
    ExpectRoundTrip(kStoresNames, ParseStores, [](Stores v) { return ToString(v); });
    ExpectRoundTrip(kConeKindNames, ParseConeKind,
                    [](ConeKind v) { return ToString(v); });
    ExpectRoundTrip(kConeEncodingNames, ParseConeEncoding,
                    [](ConeEncoding v) { return ToString(v); });
    // Channel letters keep their documented lower-case spelling.
    EXPECT_EQ(ParseChannel("g"), Channel::G);
}

TEST(EnumOption, HelpListsTheNamesAndTheDefault) {
    const fs::path d = Scratch();
    for (const EnumOptionCase& c : Cases()) {
        const std::string command = c.command.substr(0, c.command.find(' '));
        const auto r = RunCli(command + " --help", d);
        ASSERT_EQ(r.exitCode, 0) << command;
        const size_t at = r.out.find("  " + c.flag + " ");
        ASSERT_NE(at, std::string::npos) << c.flag << " in\n" << r.out;
        const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
        EXPECT_NE(line.find(" " + Join(c.names)), std::string::npos) << line;
        EXPECT_NE(line.find("="), std::string::npos) << "no default in: " << line;
    }
}

TEST(EnumOption, BadValueIsOneLineNamingOptionValueAndNames) {
    // Every option with an unknown name and an empty value (each option's own validator
    // and the empty-value check placed after it); numbers and the joined forms
    // ("--filter=", which CLI11 would read as taking the next argument) with the first
    // option of each command (they go through the parsing every option shares; each
    // case is a process, about 0.4 s of loading shared libraries).
    std::vector<std::string> seen;
    for (const EnumOptionCase& c : Cases()) {
        const std::string command = c.command.substr(0, c.command.find(' '));
        const bool first = std::find(seen.begin(), seen.end(), command) == seen.end();
        seen.push_back(command);
        std::vector<std::string> values = {"frob", ""};
        if (first) values.insert(values.end(), {"0", "1", "=", "=frob"});
        for (const std::string& bad : values) {
            const fs::path d = Scratch();
            // render requires --out; the others would write nothing here either.
            const std::string out =
                c.command.rfind("render", 0) == 0 ? " --out " + (d / "o").string() : "";
            // "=..." is the joined form, "--filter=" (CLI11 would read the next argument
            // as the value of an empty one).
            const std::string args =
                c.command + " " + c.flag + (bad[0] == '=' ? bad : " '" + bad + "'") + out;
            const std::string value = bad[0] == '=' ? bad.substr(1) : bad;
            const auto r = RunCli(args, d);
            EXPECT_NE(r.exitCode, 0) << args;
            EXPECT_EQ(CountLines(r.err), 1) << args << "\n" << r.err;
            EXPECT_NE(r.err.find(c.flag + ": \"" + value + "\" is unknown"),
                      std::string::npos)
                << args << "\n"
                << r.err;
            for (const std::string& name : c.names)
                EXPECT_NE(r.err.find("\"" + name + "\""), std::string::npos)
                    << name << " in " << r.err;
            EXPECT_FALSE(fs::exists(d / "o")) << args;
        }
    }
}

TEST(EnumOption, ChannelLettersMatchInEitherCase) {
    const fs::path d = Scratch();
    // Accepted by the parser: the refusal is the builtin map's, naming the channel.
    const auto r =
        RunCli("render --size 8x8 --map-channel r --out " + (d / "o").string(), d);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.err.find("--map-channel R: applies to image files"), std::string::npos)
        << r.err;
}
