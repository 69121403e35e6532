#pragma once
/// \file
/// `skerry align-aerial`: a LiDAR cloud registered to an aerial image by their edges
/// (frontends/lidar_aerial, docs/lidar_aerial.md).

#include "subcommand.h"

namespace skerry::cli {

Subcommand AddAlignAerialCommand(CLI::App& app);

}  // namespace skerry::cli
