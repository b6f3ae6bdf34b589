#include "drivers/module/driver_module.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <string>

namespace aprt {
namespace {

std::string module_path(const char* env_var, const char* file) {
  if (const char* env = std::getenv(env_var); env && *env) return env;
  char exe[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) return file;
  exe[n] = '\0';
  std::string dir(exe);
  dir.resize(dir.rfind('/'));
  return dir.substr(0, dir.rfind('/')) + "/lib/aprt/" + file;
}

}  // namespace

Expected<void*> open_driver_module(const char* env_var, const char* file, const char* symbol,
                                   const char* what, const char* hint) {
  const std::string path = module_path(env_var, file);
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) {
    return Error(Errc::kUnsupported, "%s: cannot load the module %s: %s (%s)", what, path.c_str(),
                 dlerror(), hint);
  }
  void* entry = dlsym(handle, symbol);
  if (!entry) {
    return Error(Errc::kUnsupported,
                 "%s: %s is not this aprt's %s module (no entry point %s); "
                 "reinstall aprt",
                 what, path.c_str(), what, symbol);
  }
  return entry;
}

}  // namespace aprt
