#pragma once
/// \file
/// `skerry report`.

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddReportCommand(CLI::App& app);

}  // namespace skerry::cli
