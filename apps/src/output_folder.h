#pragma once
/// \file
/// The rule for an --out folder: skerry never mixes new results with old ones and never replaces
/// results silently. A folder that holds any of a command's result files is refused unless the
/// user said --overwrite; then those files are removed first (the one that marks the folder
/// complete, summary.json or dataset.yaml, before the others), so that a run killed half-way
/// leaves a folder without that marker, never old and new files side by side under it.

#include <string>
#include <vector>

namespace skerry::cli {

/// What `skerry run` and `skerry smooth` write; summary.json (first) marks a complete run.
const std::vector<std::string>& RunResultFiles();
/// What a dataset writer (simulate, import) writes; dataset.yaml (first) marks a dataset.
const std::vector<std::string>& DatasetFiles();

/// Creates `folder` (and its parents) when absent. When it holds any of `result_files`: throws
/// InputError naming the folder and the file unless `overwrite`, else removes those files in
/// order, with the temporaries a killed writer left beside them. Throws InputError when `folder`
/// exists and is not a folder.
void PrepareOutputFolder(const std::string& folder,
                         const std::vector<std::string>& result_files,
                         bool overwrite);

}  // namespace skerry::cli
