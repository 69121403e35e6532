#include "export_command.h"

#include <stdexcept>

namespace skerry::cli {

// Placeholder while the command is being written (see the issue tracker).
Subcommand AddExportCommand(CLI::App& app) {
  Subcommand s;
  s.app = app.add_subcommand("export", "(not yet available)");
  s.run = []() -> int { throw std::runtime_error("skerry export is not implemented yet"); };
  return s;
}

}  // namespace skerry::cli
