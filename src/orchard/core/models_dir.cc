#include "orchard/core/models_dir.h"

#include <cstdlib>
#include <system_error>

namespace orchard {

std::filesystem::path DefaultModelsDir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("ORCHARD_MODELS_DIR"); env && *env) return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = exe.parent_path().parent_path() / "models";
    if (fs::is_directory(beside, ec)) return beside;
  }
  return fs::path(ORCHARD_SOURCE_DIR) / "models";
}

}  // namespace orchard
