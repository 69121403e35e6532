// Finds and loads libskerry_pcl_reader.so (pcl_reader.h says why PCL is loaded on demand).

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

#include "pcl_reader.h"
#include "skerry/core/input_error.h"

namespace skerry::geo::internal {
namespace {

// Where the module is looked for: $SKERRY_PCL_READER (the path of the .so) alone when it is set;
// else the build tree it was built in (tests and a build-tree CLI), then the installed copy.
std::vector<std::string> Candidates() {
  if (const char* env = std::getenv("SKERRY_PCL_READER"); env != nullptr && *env != '\0') {
    return {env};
  }
  return {SKERRY_PCL_READER_BUILD_PATH, SKERRY_PCL_READER_INSTALL_PATH};
}

struct Module {
  PclReadFunction read = nullptr;
  std::string failure;  // why it could not be loaded
};

const Module& LoadModule() {
  static Module module;
  static std::once_flag once;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : Candidates()) {
      // RTLD_LOCAL: PCL's and VTK's symbols stay out of the global scope.
      void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* why = dlerror();
        tried += "\n  " + path + ": " + (why != nullptr ? why : "cannot be loaded");
        continue;
      }
      void* symbol = dlsym(handle, kPclReadSymbol);
      if (symbol == nullptr) {
        tried += "\n  " + path + ": has no " + kPclReadSymbol;
        dlclose(handle);
        continue;
      }
      // Kept loaded for the life of the process.
      module.read = reinterpret_cast<PclReadFunction>(symbol);
      return;
    }
    module.failure = "reading PCD and PLY files needs skerry's PCL module, which was not found" +
                     tried + "\n(set SKERRY_PCL_READER to the path of libskerry_pcl_reader.so)";
  });
  return module;
}

PointCloud Read(const std::string& path, PclFormat format) {
  const Module& module = LoadModule();
  if (module.read == nullptr) throw InputError(path, 0, "", module.failure);
  PointCloud cloud;
  PclReadError error;
  if (!module.read(path, format, &cloud, &error)) {
    throw InputError(error.file, error.line, error.field, error.message);
  }
  return cloud;
}

}  // namespace

PointCloud ReadPcd(const std::string& path) { return Read(path, PclFormat::kPcd); }
PointCloud ReadPly(const std::string& path) { return Read(path, PclFormat::kPly); }

}  // namespace skerry::geo::internal
