// millwatch — the offline shell: simulate recorded cuts, replay them through the monitor,
// diagnose model/measurement gaps.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "replay/simulate_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"millwatch: micro-milling process monitor, offline tools"};
  app.require_subcommand(1);
  millwatch::shell::add_simulate_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
