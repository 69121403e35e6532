#pragma once
/// \file
/// `skerry compare` and `skerry fidelity`.

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddCompareCommand(CLI::App& app);

/// `skerry fidelity --a RUN --b RUN`: the Hellinger fidelity of two run folders.
Subcommand AddFidelityCommand(CLI::App& app);

}  // namespace skerry::cli
