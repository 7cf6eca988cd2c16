// mjtouch._core: reading a live mjtouch.skin plugin instance (its layout and
// last evaluation) through the small versioned C interface of libmjtouch.so
// (plugin/mujoco/describe.cc), looked up with dlsym in the copy MuJoCo
// already loaded. Why not compile the adapter into _core: the SkinPlugin
// objects in mjData and the kernel-table cache belong to libmjtouch.so; a
// second copy of that code here would have its own (empty) cache and could
// drift from the loaded library's class layout.
#include <dlfcn.h>

#include <cstdint>
#include <string>
#include <vector>

#include <nanobind/stl/string.h>

#include "python/convert.h"

namespace mjtouch::py {
namespace {

// Must match kInstanceAbiVersion in plugin/mujoco/describe.cc.
constexpr int kInstanceAbiVersion = 1;

using AbiFn = int (*)();
using DescribeFn = int (*)(const void* model, int instance, char* buf, int len);
using LastEvaluationFn = int (*)(const void* data, int instance, double* out8);

// `name` in the already-loaded library at `library` (never loads it).
void* Symbol(const std::string& library, const char* name) {
  void* handle = dlopen(library.c_str(), RTLD_NOW | RTLD_NOLOAD);
  if (!handle) Fail("mjtouch's plugin library " + library + " is not loaded; import mjtouch first");
  auto abi = reinterpret_cast<AbiFn>(dlsym(handle, "mjtouch_instance_abi_version"));
  void* symbol = dlsym(handle, name);
  dlclose(handle);  // only drops our reference: the loader keeps the library loaded
  if (!abi || !symbol || abi() != kInstanceAbiVersion)
    Fail("mjtouch's plugin library " + library +
         " does not match this mjtouch._core (instance "
         "interface version " +
         std::to_string(kInstanceAbiVersion) +
         " needed); was the "
         "package built? run pip install .");
  return symbol;
}

std::string Describe(const std::string& library, uintptr_t model_address, int instance) {
  auto fn = reinterpret_cast<DescribeFn>(Symbol(library, "mjtouch_describe"));
  std::vector<char> buf(1 << 16);
  const void* model = reinterpret_cast<const void*>(model_address);
  int need = fn(model, instance, buf.data(), static_cast<int>(buf.size()));
  if (need) {
    buf.resize(need);
    need = fn(model, instance, buf.data(), static_cast<int>(buf.size()));
  }
  return std::string(buf.data());
}

nb::dict LastEvaluation(const std::string& library, uintptr_t data_address, int instance) {
  auto fn = reinterpret_cast<LastEvaluationFn>(Symbol(library, "mjtouch_last_evaluation"));
  double out[8] = {0};
  if (fn(reinterpret_cast<const void*>(data_address), instance, out))
    Fail("the data has no mjtouch.skin plugin data for this instance");
  static const char* kPaths[] = {"none", "direct", "fft", "tree"};
  const int path = static_cast<int>(out[0]);
  nb::dict d;
  d["stress_method"] = kPaths[path >= 1 && path <= 3 ? path : 0];
  d["elastic_iterations"] = static_cast<int>(out[1]);
  d["elastic_converged"] = out[2] != 0;
  d["elastic_change"] = out[3];
  d["elastic_contact_cells"] = static_cast<int>(out[4]);
  d["elastic_fft_size"] = nb::make_tuple(static_cast<int>(out[5]), static_cast<int>(out[6]));
  d["active_cells"] = static_cast<int>(out[7]);
  return d;
}

}  // namespace

void BindInstance(nb::module_& m) {
  m.attr("INSTANCE_ABI_VERSION") = kInstanceAbiVersion;
  m.def("describe_instance", &Describe, nb::arg("library"), nb::arg("model_address"),
        nb::arg("instance"),
        "JSON layout (output blocks, receptor sites, substrate) of mjtouch.skin\n"
        "instance `instance` of the mjModel at model_address (MjModel._address), read\n"
        "by the loaded plugin library at path `library`.");
  m.def("last_evaluation", &LastEvaluation, nb::arg("library"), nb::arg("data_address"),
        nb::arg("instance"),
        "Diagnostics of the instance's last evaluation in the mjData at data_address\n"
        "(MjData._address): stress path, elastic solve statistics, active cells.");
}

}  // namespace mjtouch::py
