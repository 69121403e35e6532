#pragma once
/// \file
/// `skerry twin`: a digital twin of a real recording and how far the twin is from it
/// (docs/twin.md).

#include <CLI/CLI.hpp>

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddTwinCommand(CLI::App& app);

}  // namespace skerry::cli
