// Describes an mjtouch.skin instance of a compiled model: as a struct for C
// hosts (mjtouch_layout, declared in mjtouch/include/mjtouch.h) and as JSON
// with every receptor's site for Python (mjtouch_describe).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>

#include <mujoco/mujoco.h>

#include "skin_plugin.h"
// The installed public header, shipped in the Python package.
#include "../../mjtouch/include/mjtouch.h"

// The C interface mjtouch._core reads live instances through (dlsym on this
// library); bump on any change of these signatures or their meaning, with
// kInstanceAbiVersion in plugin/python/instance.cc.
constexpr int kInstanceAbiVersion = 1;
extern "C" __attribute__((visibility("default"))) int mjtouch_instance_abi_version() {
  return kInstanceAbiVersion;
}

static_assert(MJTOUCH_NUM_CLASSES == mjtouch::kNumClasses, "mjtouch.h: classes");
static_assert(MJTOUCH_NUM_BLOCKS == mjtouch::kNumOutputs, "mjtouch.h: output blocks");
static_assert(MJTOUCH_BLOCK_PRESSURE == mjtouch::kOutPressure &&
                  MJTOUCH_BLOCK_RATE == mjtouch::kOutRate,
              "mjtouch.h: output block order");

#define MJTOUCH_EXPORT extern "C" __attribute__((visibility("default")))

MJTOUCH_EXPORT int mjtouch_c_api_version(void) { return MJTOUCH_C_API_VERSION; }

MJTOUCH_EXPORT const char* mjtouch_class_name(int cls) {
  if (cls < 0 || cls >= mjtouch::kNumClasses) return nullptr;
  return mjtouch::ClassName(static_cast<mjtouch::ReceptorClass>(cls));
}

MJTOUCH_EXPORT const char* mjtouch_block_name(int block) {
  if (block < 0 || block >= mjtouch::kNumOutputs) return nullptr;
  return mjtouch::OutputName(block);
}

MJTOUCH_EXPORT int mjtouch_layout(const mjModel* m, int instance, mjtouch_layout_t* out,
                                  char* error, int error_len) {
  using namespace mjtouch;
  auto fail = [&](const std::string& message) {
    if (error && error_len > 0) std::snprintf(error, error_len, "%s", message.c_str());
    return -1;
  };
  if (!m || !out) return fail("mjtouch_layout: model and out must not be NULL");
  if (instance < 0 || instance >= m->nplugin) {
    return fail("mjtouch_layout: instance " + std::to_string(instance) +
                " is out of range; valid range [0, " + std::to_string(m->nplugin) + ")");
  }
  SkinConfig cfg;
  int sensor, pad;
  std::string read_error;
  if (!SkinPlugin::ReadConfig(m, instance, &cfg, &sensor, &pad, &read_error)) {
    return fail(read_error);
  }
  const auto sites = SkinModel::PlaceReceptors(cfg);
  mjtouch_layout_t l = {};
  l.api_version = MJTOUCH_C_API_VERSION;
  l.sensor_id = sensor;
  l.sensor_adr = m->sensor_adr[sensor];
  l.sensor_dim = m->sensor_dim[sensor];
  l.nreceptor = static_cast<int>(sites.size());
  for (int c = 0; c < kNumClasses; ++c) l.class_start[c] = -1;
  for (int r = 0; r < l.nreceptor; ++r) {
    const int c = static_cast<int>(sites[r].cls);
    // Receptors come in runs by class; a class met again after another would
    // make class_start wrong.
    if (l.class_start[c] >= 0 && l.class_start[c] + l.class_count[c] != r) {
      return fail("mjtouch_layout: receptors of class " + std::string(ClassName(sites[r].cls)) +
                  " are not contiguous");
    }
    if (l.class_start[c] < 0) l.class_start[c] = r;
    ++l.class_count[c];
  }
  // An empty class starts where the classes after it would.
  for (int c = kNumClasses - 1, next = l.nreceptor; c >= 0; --c) {
    if (l.class_start[c] < 0) l.class_start[c] = next;
    next = l.class_start[c];
  }
  int adr = l.sensor_adr;
  for (int b = 0; b < kNumOutputs; ++b) {
    l.block_size[b] = SkinModel::BlockSize(cfg, l.nreceptor, b);
    l.block_adr[b] = l.block_size[b] ? adr : -1;
    adr += l.block_size[b];
  }
  l.nx = cfg.grid.n;
  l.pitch_m = cfg.grid.pitch_m;
  l.oversample = cfg.oversample;
  *out = l;
  return 0;
}

MJTOUCH_EXPORT int mjtouch_describe(const mjModel* m, int instance, char* buf, int len) {
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
      js << (first ? "" : ", ") << "{\"name\": \"" << OutputName(b) << "\", \"offset\": " << offset
         << ", \"size\": " << size << "}";
      offset += size;
      first = false;
    }
    js << "], \"receptors\": [";
    for (int r = 0; r < nrec; ++r) {
      const auto& s = sites[r];
      js << (r ? ", " : "") << "[\"" << ClassName(s.cls) << "\", " << s.x_m << ", " << s.y_m << ", "
         << s.depth_m << "]";
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
extern "C" __attribute__((visibility("default"))) int mjtouch_last_evaluation(const mjData* d,
                                                                              int instance,
                                                                              double* out8) {
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
