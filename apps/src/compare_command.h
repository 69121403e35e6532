#pragma once
/// \file
/// `skerry compare`.

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddCompareCommand(CLI::App& app);

}  // namespace skerry::cli
