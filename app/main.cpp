// reliefsim: the command line.
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "core/param_name.h"

namespace {

/// Every error is one line: embedded newlines (third-party messages) become "; ".
void PrintError(const std::string& message) {
    std::fprintf(stderr, "reliefsim: error: %s\n", reliefsim::OneLine(message).c_str());
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
    // An option given an empty value ("--out ''", "--out=": an unset shell variable,
    // say) is a mistake, never "the default" nor "none": refused, naming the option,
    // before any command looks at it.
    for (int i = 2; i < argc; ++i) {
        const std::string arg = argv[i], prev = argv[i - 1];
        const bool emptyAfter = arg.empty() && prev.rfind("--", 0) == 0 &&
                                prev.size() > 2 && prev.find('=') == std::string::npos;
        const bool emptyJoined = arg.rfind("--", 0) == 0 && arg.size() > 3 &&
                                 arg.back() == '=' && arg.find('=') == arg.size() - 1;
        if (emptyAfter || emptyJoined) {
            const std::string opt = emptyJoined ? arg.substr(0, arg.size() - 1) : prev;
            // An enumerated option names its values itself ("" is unknown; must be one
            // of ...): left to it.
            const CLI::Option* o =
                known ? app.get_subcommand(argv[1])->get_option_no_throw(opt) : nullptr;
            if (o && o->get_type_name().find('|') != std::string::npos) continue;
            PrintError(opt + ": empty value; give one, or leave " + opt + " out");
            return 2;
        }
    }
    try {
        app.parse(argc, argv);
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
