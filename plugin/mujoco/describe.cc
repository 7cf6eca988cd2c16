// Describes an mjtouch.skin instance of a compiled model as JSON (output
// blocks, receptor sites), so Python reads sensordata by name.
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

#include <mujoco/mujoco.h>

#include "skin_plugin.h"

// The C interface mjtouch._core reads live instances through (dlsym on this
// library); bump on any change of these signatures or their meaning, with
// kInstanceAbiVersion in plugin/python/instance.cc.
constexpr int kInstanceAbiVersion = 1;
extern "C" __attribute__((visibility("default"))) int mjtouch_instance_abi_version() {
  return kInstanceAbiVersion;
}

extern "C" __attribute__((visibility("default"))) int mjtouch_describe(const mjModel* m,
                                                                      int instance, char* buf,
                                                                      int len) {
  using namespace mjtouch;
  SkinConfig cfg;
  int sensor, pad;
  std::string error;
  std::ostringstream js;
  js.precision(17);
  if (!SkinPlugin::ReadConfig(m, instance, &cfg, &sensor, &pad, &error)) {
    js << "{\"error\": \"" << error << "\"}";
  } else {
    const auto sites = SkinModel::PlaceReceptors(cfg);
    const int nrec = static_cast<int>(sites.size());
    js << "{\"sensor_id\": " << sensor << ", \"sensor_adr\": " << m->sensor_adr[sensor]
       << ", \"pad_geom\": " << pad << ", \"nx\": " << cfg.grid.n
       << ", \"pitch_m\": " << cfg.grid.pitch_m << ", \"blocks\": [";
    int offset = 0;
    bool first = true;
    for (int b = 0; b < kNumOutputs; ++b) {
      const int size = SkinModel::BlockSize(cfg, nrec, b);
      if (!size) continue;
      js << (first ? "" : ", ") << "{\"name\": \"" << OutputName(b) << "\", \"offset\": "
         << offset << ", \"size\": " << size << "}";
      offset += size;
      first = false;
    }
    js << "], \"receptors\": [";
    for (int r = 0; r < nrec; ++r) {
      const auto& s = sites[r];
      js << (r ? ", " : "") << "[\"" << ClassName(s.cls) << "\", " << s.x_m << ", " << s.y_m
         << ", " << s.depth_m << "]";
    }
    js << "], \"oversample\": " << cfg.oversample << ", \"quantity\": [";
    for (int c = 0; c < kNumClasses; ++c)
      js << (c ? ", " : "") << "\"" << QuantityName(cfg.classes[c].quantity) << "\"";
    js << "]";
    // The elastic skin and the time its kernel tables took to build (once per
    // configuration: found in the cache while an MjData of the model lives).
    std::string build_error;
    if (const auto model = SkinModel::Build(cfg, &build_error)) {
      js << ", \"substrate\": \"" << model->substrate().Describe()
         << "\", \"kernel_build_s\": " << model->kernel_build_seconds()
         << ", \"fft_spectra\": " << (model->spectra() ? "true" : "false");
    }
    js << "}";
  }
  const std::string s = js.str();
  if (static_cast<int>(s.size()) + 1 > len) return static_cast<int>(s.size()) + 1;
  std::memcpy(buf, s.c_str(), s.size() + 1);
  return 0;
}

// Diagnostics of an instance's last evaluation in `d` (scratch, not state):
// out8 = stress path (1 direct, 2 fft, 3 tree), elastic iterations,
// converged, last relative change, contact cells, FFT size x, y, active
// traction cells. Returns 0, or 1 if the instance has no plugin data.
extern "C" __attribute__((visibility("default"))) int mjtouch_last_evaluation(
    const mjData* d, int instance, double* out8) {
  using namespace mjtouch;
  const SkinPlugin* p = SkinPlugin::Owned(d, instance);
  if (!p) return 1;
  const Workspace& w = p->workspace();
  out8[0] = static_cast<int>(w.last_stress_method);
  out8[1] = w.elastic_stats.iterations;
  out8[2] = w.elastic_stats.converged;
  out8[3] = w.elastic_stats.change;
  out8[4] = w.elastic_stats.contact_cells;
  out8[5] = w.elastic_stats.fft_size_x;
  out8[6] = w.elastic_stats.fft_size_y;
  out8[7] = w.traction.active_cells;
  return 0;
}
