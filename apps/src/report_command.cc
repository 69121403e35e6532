#include "report_command.h"

#include <stdexcept>

namespace skerry::cli {

// Placeholder while the command is being written (see the issue tracker).
Subcommand AddReportCommand(CLI::App& app) {
  Subcommand s;
  s.app = app.add_subcommand("report", "(not yet available)");
  s.run = []() -> int { throw std::runtime_error("skerry report is not implemented yet"); };
  return s;
}

}  // namespace skerry::cli
