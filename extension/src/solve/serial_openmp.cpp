#include "serial_openmp.h"

#include <dlfcn.h>

namespace torsion::detail {

namespace {
// The OpenMP runtime CHOLMOD loaded, looked up by name rather than linked: the library then
// depends on no OpenMP runtime of its own, and it finds GNU's or LLVM's, whichever SuiteSparse
// was built with, also when it is loaded into a process privately (a Python module).
struct OpenMpRuntime {
  int (*get_max_active_levels)() = nullptr;
  void (*set_max_active_levels)(int) = nullptr;
};

OpenMpRuntime lookUpRuntime() {
  OpenMpRuntime runtime;
  for (const char* name : {"libgomp.so.1", "libomp.so.5", "libomp.so"}) {
    void* library = dlopen(name, RTLD_LAZY | RTLD_NOLOAD);  // only if already loaded
    if (library == nullptr) continue;
    runtime.get_max_active_levels =
        reinterpret_cast<int (*)()>(dlsym(library, "omp_get_max_active_levels"));
    runtime.set_max_active_levels =
        reinterpret_cast<void (*)(int)>(dlsym(library, "omp_set_max_active_levels"));
    dlclose(library);  // the reference RTLD_NOLOAD took; the runtime stays loaded by its users
    if (runtime.get_max_active_levels != nullptr && runtime.set_max_active_levels != nullptr)
      return runtime;
    runtime = OpenMpRuntime{};
  }
  return runtime;
}

const OpenMpRuntime& runtime() {
  static const OpenMpRuntime loaded = lookUpRuntime();
  return loaded;
}
}  // namespace

SerialOpenMpScope::SerialOpenMpScope() {
  const OpenMpRuntime& omp = runtime();
  if (omp.set_max_active_levels == nullptr) return;
  saved_levels_ = omp.get_max_active_levels();
  omp.set_max_active_levels(0);
}

SerialOpenMpScope::~SerialOpenMpScope() {
  if (saved_levels_ >= 0) runtime().set_max_active_levels(saved_levels_);
}

}  // namespace torsion::detail
