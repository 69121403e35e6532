#include "compare_command.h"

#include <stdexcept>

namespace skerry::cli {

// Placeholder while the command is being written (see the issue tracker).
Subcommand AddCompareCommand(CLI::App& app) {
  Subcommand s;
  s.app = app.add_subcommand("compare", "(not yet available)");
  s.run = []() -> int { throw std::runtime_error("skerry compare is not implemented yet"); };
  return s;
}

}  // namespace skerry::cli
