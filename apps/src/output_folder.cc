#include "output_folder.h"

#include <filesystem>
#include <system_error>

#include "skerry/core/input_error.h"

namespace skerry::cli {

namespace fs = std::filesystem;

const std::vector<std::string>& RunResultFiles() {
  static const std::vector<std::string> kFiles = {"summary.json", "trajectory.tum",
                                                  "states.csv",   "covariances.csv",
                                                  "updates.csv",  "blocks.csv"};
  return kFiles;
}

const std::vector<std::string>& DatasetFiles() {
  // docs/dataset-format.md; camera and LiDAR frame lists are named by their sensors and are
  // replaced whole by the writer.
  static const std::vector<std::string> kFiles = {"dataset.yaml",
                                                  "imu.csv",
                                                  "gnss.csv",
                                                  "groundtruth.tum",
                                                  "truth_states.csv",
                                                  "pose_fixes.csv",
                                                  "pose_fix_outliers.csv",
                                                  "events.csv",
                                                  "heading.csv",
                                                  "course.csv",
                                                  "attitude.csv",
                                                  "rate_of_turn.csv"};
  return kFiles;
}

void PrepareOutputFolder(const std::string& folder,
                         const std::vector<std::string>& result_files,
                         bool overwrite) {
  const fs::path dir(folder);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw InputError(folder, 0, "--out", "exists and is not a folder");
  }
  for (const std::string& name : result_files) {
    if (!fs::exists(dir / name, ec)) continue;
    if (!overwrite) {
      throw InputError(folder, 0, "--out",
                       "already holds results (" + name +
                           "); give --overwrite to replace them, or another --out folder");
    }
    break;
  }
  if (overwrite) {
    for (const std::string& name : result_files) {
      fs::remove(dir / name, ec);
      if (ec) {
        throw InputError((dir / name).string(), 0, "--overwrite", "cannot remove: " + ec.message());
      }
    }
    // Temporaries a killed writer left (atomic_file.h: "<name>.partial-<pid>").
    if (fs::is_directory(dir, ec)) {
      for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
        const std::string file = e.path().filename().string();
        for (const std::string& name : result_files) {
          if (file.rfind(name + ".partial-", 0) == 0) fs::remove(e.path(), ec);
        }
      }
    }
  }
  fs::create_directories(dir, ec);
  if (ec) throw InputError(folder, 0, "--out", "cannot create the folder: " + ec.message());
}

}  // namespace skerry::cli
