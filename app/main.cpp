// reliefsim: the command line.
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "core/error.h"

int main(int argc, char** argv) {
    using namespace reliefsim;
    CLI::App app{
        "reliefsim: simulate, on the CPU, how a GPU runs height-field ray-intersection "
        "fragment shaders, counting every fetch"};
    app.require_subcommand(1);
    RegisterMethodsCommand(app);
    RegisterRenderCommand(app);
    RegisterSummaryCommand(app);
    RegisterTraceCommand(app);
#ifdef RS_HAVE_MAPS_COMMAND
    RegisterMapsCommand(app);
#endif
#ifdef RS_HAVE_GLCOMPARE_COMMAND
    RegisterGlCompareCommand(app);
#endif
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One line, like every other error (CLI11's own report takes two).
        std::fprintf(stderr, "reliefsim: error: %s; run with --help for usage\n", e.what());
        return 2;
    } catch (const Error& e) {
        std::fprintf(stderr, "reliefsim: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "reliefsim: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
