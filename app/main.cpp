// reliefsim: the command line.
#include <cstdio>
#include <exception>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/enum_option.h"
#include "core/error.h"
#include "core/param_name.h"
#include "core/parse.h"

namespace {

/// Every error is one line: embedded newlines (third-party messages) become "; ".
void PrintError(const std::string& message) {
    std::fprintf(stderr, "reliefsim: error: %s\n", reliefsim::OneLine(message).c_str());
}

/// `fn` for every option that takes a value, of `app` and of all its subcommands.
void ForEachValueOption(CLI::App& app, const std::function<void(CLI::Option*)>& fn) {
    for (CLI::Option* o :
         app.get_options([](const CLI::Option* o) { return o->get_expected_min() > 0; }))
        fn(o);
    for (CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        ForEachValueOption(*sub, fn);
}

/// An option given an empty value ("--out ''", an unset shell variable) is a mistake,
/// never "the default" nor "none": every option of every command that takes a value
/// refuses one, naming the option, before its other checks ("--threads: Value not in
/// range"), except that an enumerated option lists its names itself ("" is unknown;
/// must be one of ...).
void RefuseEmptyValues(CLI::App& app) {
    ForEachValueOption(app, [](CLI::Option* o) {
        const CLI::Validator empty(
            [name = o->get_name()](const std::string& value) {
                return value.empty() ? "empty value; give one, or leave " + name + " out"
                                     : std::string();
            },
            /*validator_desc=*/"");
        bool listsNames = true;
        try {  // CLI11 has no lookup that does not throw
            o->get_validator(reliefsim::kEnumValidatorName);
        } catch (const CLI::OptionNotFound&) {
            listsNames = false;
        }
        if (listsNames)
            o->check(empty);  // after the names'
        else
            o->transform(empty);  // first
    });
}

/// Numbers on the command line are decimal, by the same rules as --set, --size and the
/// other options core/parse.h reads: CLI11 alone reads "0x10" as 16, "010" as 8 (octal),
/// "0x1p3" as 8 and "+5" as 5, and refuses "5 " as out of range. Every integer option
/// (type INT...) takes an optional '-' and decimal digits, handed on without leading
/// zeros ("010" is 10); every floating-point one (FLOAT...) takes what std::from_chars
/// reads as a decimal number, whole (nan, inf and values out of range go on to the
/// option's own checks, which name them). Applied first, after the empty-value check,
/// which passes "" on.
void RequireDecimalNumbers(CLI::App& app) {
    ForEachValueOption(app, [](CLI::Option* o) {
        const std::string type = o->get_type_name();
        const bool integer = type.rfind("INT", 0) == 0;
        if (!integer && type.rfind("FLOAT", 0) != 0) return;
        o->transform(CLI::Validator(
            [integer](std::string& value) -> std::string {
                if (value.empty()) return {};
                if (integer) {
                    if (!reliefsim::LooksLikeInteger(value))
                        return "\"" + value + "\" is not a decimal integer";
                    // Out of int64: left as it is, for the option's range message.
                    if (const auto v = reliefsim::ParseInt64(value))
                        value = std::to_string(*v);
                    return {};
                }
                if (!reliefsim::LooksLikeDecimal(value))
                    return "\"" + value + "\" is not a decimal number";
                return {};
            },
            /*validator_desc=*/""));
    });
}

/// "--opt=" as "--opt ''" for an option that takes a value (CLI11 would take the next
/// argument as its value); a flag's "--quiet=" is refused (CLI11 would set the flag).
std::vector<std::string> SplitEmptyJoined(const CLI::App& app, int argc, char** argv) {
    std::vector<std::string> args(argv, argv + argc);
    const CLI::App* cmd = &app;
    for (size_t i = 1; i < args.size(); ++i) {
        if (args[i] == "--") break;  // the rest are not options
        const auto subs = cmd->get_subcommands(
            [&](const CLI::App* sub) { return sub->get_name() == args[i]; });
        if (!subs.empty()) {
            cmd = subs.front();
            continue;
        }
        if (args[i].size() < 4 || args[i].rfind("--", 0) != 0 ||
            args[i].find('=') != args[i].size() - 1)
            continue;
        const std::string name = args[i].substr(0, args[i].size() - 1);
        const CLI::Option* o = cmd->get_option_no_throw(name);
        if (o && o->get_expected_min() == 0)  // "--quiet=$UNSET": not "--quiet"
            throw CLI::ValidationError(
                name, "empty value; give " + name + " alone, or leave it out");
        args[i] = name;
        args.insert(args.begin() + std::ptrdiff_t(i) + 1, std::string());
        ++i;
    }
    return args;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace reliefsim;
    // Library errors name their parameters; here they are the command line's flags.
    SetParamNamer(&FlagName);
    CLI::App app{
        "reliefsim: simulate, on the CPU, how a GPU runs height-field ray-intersection "
        "fragment shaders, counting every fetch"};
    app.require_subcommand(1);
    RegisterMethodsCommand(app);
    RegisterRenderCommand(app);
    RegisterSummaryCommand(app);
    RegisterTraceCommand(app);
    RegisterMapsCommand(app);
    RegisterSweepCommand(app);
    RegisterSafetyCommand(app);
#ifdef RS_HAVE_GLCOMPARE_COMMAND
    RegisterGlCompareCommand(app);
#endif
    // An unknown first word is named, with the commands that exist (CLI11 would only say
    // that a subcommand is required).
    std::string names;
    bool known = false;
    for (const CLI::App* sub :
         app.get_subcommands([](const CLI::App*) { return true; })) {
        names += (names.empty() ? "" : ", ") + sub->get_name();
        known = known || (argc >= 2 && sub->get_name() == argv[1]);
    }
    if (argc >= 2 && argv[1][0] != '-' && !known) {
        PrintError(std::string("\"") + argv[1] +
                   "\": unknown command; the commands are: " + names +
                   " (reliefsim COMMAND --help for each)");
        return 2;
    }
    try {
        RefuseEmptyValues(app);
        RequireDecimalNumbers(app);
        std::vector<std::string> args = SplitEmptyJoined(app, argc, argv);
        std::vector<char*> argp;
        for (std::string& a : args) argp.push_back(a.data());
        app.parse(int(argp.size()), argp.data());
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        PrintError(std::string(e.what()) + "; run with --help for usage");
        return 2;
    } catch (const Error& e) {
        PrintError(e.what());
        return 1;
    } catch (const std::bad_alloc&) {
        PrintError(
            "out of memory; the run needs more memory than this machine has (try a "
            "smaller --size or map)");
        return 1;
    } catch (const std::exception& e) {
        PrintError(e.what());
        return 1;
    }
    return 0;
}
