// The whole tactile pipeline for one fingertip, independent of MuJoCo:
//   surface/   (stage 1) skin and counter-surface geometry -> gap per taxel
//   contact/   (stage 2) gap + contact force -> pressure and shear tractions
//   stress/    (stage 3) tractions -> stress tensor at receptor sites
//   afferents/ (stage 4) stress -> SA1 / RA / PC spikes
// This umbrella header gathers the pipeline's parts:
//   attributes.h  the MJCF attribute table: keys, parsing, ranges, docs, cache key
//   config.h      SkinConfig and the checks that need the pad or timestep
//   model.h       SkinModel (immutable, shared by every MjData of a model)
//   state_layout.h  the layout of the per-step state (MuJoCo plugin_state)
//   step.h        StepInput, Workspace (MuJoCo plugin_data scratch) and Step
// and elastic/ holds how the pipeline drives the `elastic` contact solver:
// warm starts from the pressure history, the growing solve box, `grid_shift`.
#ifndef MJTOUCH_PIPELINE_SKIN_H_
#define MJTOUCH_PIPELINE_SKIN_H_

#include "pipeline/attributes.h"
#include "pipeline/config.h"
#include "pipeline/model.h"
#include "pipeline/state_layout.h"
#include "pipeline/step.h"

#endif  // MJTOUCH_PIPELINE_SKIN_H_
