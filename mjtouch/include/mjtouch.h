/* mjtouch.h: the C interface of the mjtouch.skin MuJoCo sensor plugin.
 *
 * A C or C++ host loads the plugin library (libmjtouch.so, installed in the
 * mjtouch Python package) with mj_loadPluginLibrary, compiles a model that
 * uses the plugin, and reads each skin's sensordata through the layout this
 * header describes. `python -m mjtouch --include` prints the directory of this
 * header; `python -c "import mjtouch; print(mjtouch.library_path())"` the
 * library to load (and to link, or to dlopen, for the functions below).
 *
 * Sensordata of one skin, from m->sensor_adr of its sensor: the enabled
 * output blocks in the order of mjtouch_block_t. In the per-receptor blocks
 * (spikes, stress, voltage, rate) receptors are ordered by class, SA1 first,
 * then RA, then PC; class_start and class_count give each class's run. */
#ifndef MJTOUCH_H_
#define MJTOUCH_H_

#include <mujoco/mujoco.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped on any change of the declarations below or of their meaning. A host
 * compares it with mjtouch_c_api_version() of the library it loaded. */
#define MJTOUCH_C_API_VERSION 2

/* Receptor classes, in their sensordata order. */
typedef enum mjtouch_class_ {
  MJTOUCH_SA1 = 0, /* slowly adapting type 1 (Merkel) */
  MJTOUCH_RA = 1,  /* rapidly adapting (Meissner) */
  MJTOUCH_PC = 2,  /* Pacinian */
  MJTOUCH_NUM_CLASSES = 3
} mjtouch_class_t;

/* Output blocks, in their sensordata order (disabled ones take no room). */
typedef enum mjtouch_block_ {
  MJTOUCH_BLOCK_SPIKES = 0,   /* spikes per receptor in the step (count) */
  MJTOUCH_BLOCK_STRESS = 1,   /* receptor quantity per receptor (Pa, or J/m^3, or strain) */
  MJTOUCH_BLOCK_VOLTAGE = 2,  /* membrane potential over threshold per receptor */
  MJTOUCH_BLOCK_FORCE = 3,    /* normal, tangential x, y (N, pad frame), indentation (m) */
  MJTOUCH_BLOCK_PRESSURE = 4, /* nx * nx taxel pressures (Pa), row-major */
  MJTOUCH_BLOCK_RATE = 5,     /* smoothed firing rate per receptor (Hz) */
  MJTOUCH_BLOCK_COVERAGE = 6, /* share of MuJoCo's normal force on the pad on the skin's patch,
                                 and that normal force (N) */
  MJTOUCH_BLOCK_STICK = 7,    /* shear="partial": nx * nx, 1 stick, 0 slip, -1 unloaded */
  MJTOUCH_BLOCK_SLIP = 8,     /* shear="partial": stuck share, mu, shift x, y (m) */
  MJTOUCH_BLOCK_SHEAR = 9,    /* 2 * nx * nx tangential tractions x then y (Pa, pad frame) */
  MJTOUCH_NUM_BLOCKS = 10
} mjtouch_block_t;

/* The layout of one skin (one mjtouch.skin plugin instance). */
typedef struct mjtouch_layout_ {
  int api_version;                      /* MJTOUCH_C_API_VERSION of the library */
  int sensor_id;                        /* the skin's sensor in m */
  int sensor_adr;                       /* m->sensor_adr[sensor_id] */
  int sensor_dim;                       /* its values in d->sensordata */
  int nreceptor;                        /* receptors of all classes */
  int class_count[MJTOUCH_NUM_CLASSES]; /* receptors per class */
  int class_start[MJTOUCH_NUM_CLASSES]; /* first receptor of each class */
  int block_adr[MJTOUCH_NUM_BLOCKS];    /* index in d->sensordata, -1 if disabled */
  int block_size[MJTOUCH_NUM_BLOCKS];   /* values in the block, 0 if disabled */
  int nx;                               /* taxel grid is nx x nx */
  double pitch_m;                       /* taxel pitch (m) */
  int oversample;                       /* tactile evaluations per physics step */
} mjtouch_layout_t;

/* MJTOUCH_C_API_VERSION the library was built with. */
int mjtouch_c_api_version(void);

/* Fills `out` with the layout of plugin instance `instance` of `m` (for the
 * skin sensor i: instance = m->sensor_plugin[i]). Returns 0, or -1 if the
 * instance is not a valid mjtouch.skin; then, if error_len > 0, `error`
 * receives a NUL-terminated message (cut to error_len). */
int mjtouch_layout(const mjModel* m, int instance, mjtouch_layout_t* out, char* error,
                   int error_len);

/* "SA1", "RA", "PC"; NULL out of range. */
const char* mjtouch_class_name(int cls);

/* "spikes", "stress", "voltage", "force", "pressure", "rate", "coverage", "stick", "slip",
 * "shear"; NULL out of range. */
const char* mjtouch_block_name(int block);

/* The layout as JSON, with every receptor's class and site (x, y, depth in m):
 * writes it to buf and returns 0 if it fits in len bytes, else returns the
 * length needed (with the NUL). What the Python package reads. */
int mjtouch_describe(const mjModel* m, int instance, char* buf, int len);

#ifdef __cplusplus
}
#endif

#endif /* MJTOUCH_H_ */
