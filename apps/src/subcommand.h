#pragma once
/// \file
/// A subcommand registered on the skerry CLI: each command file adds its own options to the
/// app and returns the action main runs when that subcommand was given.

#include <CLI/CLI.hpp>
#include <functional>

namespace skerry::cli {

struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

}  // namespace skerry::cli
