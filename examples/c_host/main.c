/* A C host of the mjtouch.skin plugin: loads a scene, presses the finger and
 * slides it, and prints each skin's receptors and spikes per class, read
 * through mjtouch.h (no JSON, no Python).
 *
 *   make -C examples/c_host
 *   examples/c_host/c_host models/slide_grating.xml 2000 0.5 0.025
 *
 * Arguments: scene, steps, press force (N, on an actuator named "press"),
 * slide speed (m/s, on an actuator named "slide"); the scene's own controls
 * are kept where it has no such actuator. Linking libmjtouch.so registers the
 * plugin when the program starts (as mj_loadPluginLibrary would). */
#include <stdio.h>
#include <stdlib.h>

#include <mujoco/mujoco.h>

#include "mjtouch.h"

static void set_control(const mjModel* m, mjData* d, const char* name, double value) {
  const int id = mj_name2id(m, mjOBJ_ACTUATOR, name);
  if (id >= 0) d->ctrl[id] = value;
}

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s SCENE.xml [steps] [press_n] [speed_m_s]\n", argv[0]);
    return 2;
  }
  const int steps = argc > 2 ? atoi(argv[2]) : 1000;
  const double press_n = argc > 3 ? atof(argv[3]) : 0.5;
  const double speed_m_s = argc > 4 ? atof(argv[4]) : 0.025;
  if (steps < 0) {
    fprintf(stderr, "steps %d must be >= 0\n", steps);
    return 2;
  }
  if (mjtouch_c_api_version() != MJTOUCH_C_API_VERSION) {
    fprintf(stderr, "libmjtouch has C API %d, this program was built for %d\n",
            mjtouch_c_api_version(), MJTOUCH_C_API_VERSION);
    return 1;
  }

  char error[1000] = "";
  mjModel* m = mj_loadXML(argv[1], NULL, error, sizeof(error));
  if (!m) {
    fprintf(stderr, "%s: %s\n", argv[1], error);
    return 1;
  }
  mjData* d = mj_makeData(m);

  /* The layout of every skin: one per mjtouch.skin sensor. */
  int nskin = 0;
  mjtouch_layout_t* skins = calloc(m->nsensor ? m->nsensor : 1, sizeof(mjtouch_layout_t));
  const char** names = calloc(m->nsensor ? m->nsensor : 1, sizeof(const char*));
  for (int i = 0; i < m->nsensor; ++i) {
    if (m->sensor_type[i] != mjSENS_PLUGIN) continue;
    if (mjtouch_layout(m, m->sensor_plugin[i], &skins[nskin], error, sizeof(error))) {
      fprintf(stderr, "sensor %d: %s\n", i, error);
      return 1;
    }
    names[nskin] = mj_id2name(m, mjOBJ_SENSOR, i);
    ++nskin;
  }

  /* Spikes per skin and class over the run. */
  double (*spikes)[MJTOUCH_NUM_CLASSES] = calloc(nskin ? nskin : 1, sizeof(*spikes));
  set_control(m, d, "press", -press_n);
  set_control(m, d, "slide", speed_m_s);
  for (int t = 0; t < steps; ++t) {
    mj_step(m, d);
    for (int s = 0; s < nskin; ++s) {
      const mjtouch_layout_t* l = &skins[s];
      if (l->block_adr[MJTOUCH_BLOCK_SPIKES] < 0) continue;
      const mjtNum* count = d->sensordata + l->block_adr[MJTOUCH_BLOCK_SPIKES];
      for (int c = 0; c < MJTOUCH_NUM_CLASSES; ++c) {
        for (int r = l->class_start[c]; r < l->class_start[c] + l->class_count[c]; ++r) {
          spikes[s][c] += count[r];
        }
      }
    }
  }

  printf("scene %s: %d skin(s), %d steps of %g s\n", argv[1], nskin, steps, m->opt.timestep);
  for (int s = 0; s < nskin; ++s) {
    const mjtouch_layout_t* l = &skins[s];
    printf("skin %s: %d receptors, %dx%d taxels of %g m, sensordata [%d, %d)\n",
           names[s] ? names[s] : "?", l->nreceptor, l->nx, l->nx, l->pitch_m, l->sensor_adr,
           l->sensor_adr + l->sensor_dim);
    for (int b = 0; b < MJTOUCH_NUM_BLOCKS; ++b) {
      if (l->block_size[b]) {
        printf("  block %s adr %d size %d\n", mjtouch_block_name(b), l->block_adr[b],
               l->block_size[b]);
      }
    }
    for (int c = 0; c < MJTOUCH_NUM_CLASSES; ++c) {
      printf("  class %s count %d start %d spikes %.0f\n", mjtouch_class_name(c), l->class_count[c],
             l->class_start[c], spikes[s][c]);
    }
  }
  free(spikes);
  free(names);
  free(skins);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
