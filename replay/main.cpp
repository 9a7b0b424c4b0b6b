// millwatch — the offline shell: simulate recorded cuts, replay them through the monitor,
// diagnose model/measurement gaps.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "replay/calibrate_command.hpp"
#include "replay/diagnose_command.hpp"
#include "replay/publish_command.hpp"
#include "replay/replay_command.hpp"
#include "replay/simulate_command.hpp"

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results (summaries as JSON).
  spdlog::set_default_logger(spdlog::stderr_color_mt("millwatch"));
  CLI::App app{"millwatch: micro-milling process monitor, offline tools"};
  app.require_subcommand(1);
  millwatch::shell::add_simulate_command(app);
  millwatch::shell::add_replay_command(app);
  millwatch::shell::add_publish_command(app);
  millwatch::shell::add_calibrate_command(app);
  millwatch::shell::add_diagnose_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
