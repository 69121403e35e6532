#pragma once
/// \file
/// `skerry export`.

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddExportCommand(CLI::App& app);

}  // namespace skerry::cli
