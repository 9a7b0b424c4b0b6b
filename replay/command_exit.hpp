#pragma once
// How a subcommand ends: an exception is logged as an error and the program exits with code 2;
// a non-zero return exits with that code (CLI11 turns CLI::RuntimeError into the exit code).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <exception>

namespace millwatch::shell {

template <class Body>
void run_subcommand(Body&& body) {
  int rc = 0;
  try {
    rc = body();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    rc = 2;
  }
  if (rc != 0) {
    throw CLI::RuntimeError(rc);
  }
}

}  // namespace millwatch::shell
