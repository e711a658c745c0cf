// `orchard <task> [--option value]`: one program, one subcommand per task.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"

int main(int argc, char** argv) {
  CLI::App app{
      "orchard: apple yield of an orchard row from two videos, one from each side.\n"
      "Run `orchard <task> --help` for a task's options."};
  app.name("orchard");
  app.require_subcommand(1);
  app.set_version_flag("--version", ORCHARD_VERSION);

  // --- subcommands (one line each) ---
  orchard::AddDemoCommand(app);
  orchard::AddConvertCommand(app);
  orchard::AddSynthCommand(app);
  orchard::AddEvalCommand(app);
  orchard::AddTrainCommand(app);
  orchard::AddDetectCommand(app);
  orchard::AddCountCommand(app);
  orchard::AddSideCommand(app);
  orchard::AddYieldCommand(app);
  orchard::AddCalibrateCommand(app);
  orchard::AddTrainNetworkCommands(app);  // after AddTrainCommand: adds to `train`
  orchard::AddPatchesCommand(app);
  orchard::AddSplitCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const orchard::Error& e) {
    std::fprintf(stderr, "orchard: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "orchard: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
