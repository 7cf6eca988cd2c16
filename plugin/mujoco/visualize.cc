// Drawing the skin in MuJoCo's scene (the plugin's visualize callback, so it
// shows in any viewer, `python -m mujoco.viewer` included): the last
// evaluation's pressure field as a heatmap of tiles, and the receptor sites,
// which flash in their class colour for kFlashS after each spike. Reads only
// what Compute left in this object; draws nothing the physics depends on.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pad_frame.h"
#include "skin_plugin.h"

namespace mjtouch {
namespace {

constexpr int kMaxTilesPerSide = 32;      // finer grids are drawn in binned tiles
constexpr double kMinRelPressure = 0.02;  // tiles under 2% of the peak are not drawn
constexpr double kFlashS = 0.03;          // s a spike stays lit (~2 frames at 60 Hz)
constexpr double kTileHalfThickM = 2e-5;  // m
constexpr double kAboveGapM = 2e-3;       // m: the `above` copy floats this far over the pad
constexpr double kLitRadiusM = 1.2e-4;    // m, a receptor that just fired
constexpr double kIdleRadiusM = 4e-5;     // m, a quiet receptor site

// Heat ramp (low -> high): dark red, red, orange, yellow, near white.
void HeatColor(double u, float rgba[4]) {
  const double v = 0.2 + 0.8 * std::clamp(u, 0.0, 1.0);
  rgba[0] = static_cast<float>(std::clamp(3.0 * v, 0.0, 1.0));
  rgba[1] = static_cast<float>(std::clamp(3.0 * v - 1.0, 0.0, 1.0));
  rgba[2] = static_cast<float>(std::clamp(3.0 * v - 2.0, 0.0, 1.0));
  rgba[3] = 1.0f;
}

// Class colours lie outside the heat ramp: SA1 blue, RA green, PC magenta.
constexpr float kClassRgba[kNumClasses][4] = {
    {0.15f, 0.45f, 1.0f, 1.0f}, {0.1f, 0.9f, 0.25f, 1.0f}, {0.95f, 0.2f, 0.95f, 1.0f}};
constexpr float kIdleRgba[4] = {0.35f, 0.35f, 0.38f, 1.0f};
constexpr float kBackingRgba[4] = {0.08f, 0.08f, 0.1f, 0.55f};
constexpr float kRidgeRgba[4] = {0.85f, 0.85f, 0.9f, 0.6f};  // ridge crests, `above` copy
constexpr double kRidgeLineWidthPx = 1.5;                    // ridge crest lines, pixels

bool AddGeom(mjvScene* scn, int type, const mjtNum size[3], const mjtNum pos[3],
             const mjtNum mat[9], const float rgba[4], int sensor_id) {
  if (scn->ngeom >= scn->maxgeom) {
    if (!scn->status) {
      mju_warning("mjtouch.skin: the scene's geom buffer is full; increase maxgeom above %d",
                  scn->maxgeom);
      scn->status = 1;
    }
    return false;
  }
  mjvGeom* g = scn->geoms + scn->ngeom;
  mjv_initGeom(g, type, size, pos, mat, rgba);
  g->objtype = mjOBJ_UNKNOWN;
  g->objid = sensor_id;
  g->category = mjCAT_DECOR;
  g->segid = scn->ngeom;
  scn->ngeom++;
  return true;
}

}  // namespace

void SkinPlugin::Visualize(const mjModel* m, mjData* d, const mjvOption* opt, mjvScene* scn,
                           int instance) const {
  if (visual_ == VisualMode::kNone) return;
  const bool on_pad = visual_ == VisualMode::kPad || visual_ == VisualMode::kBoth;
  const bool above = visual_ == VisualMode::kAbove || visual_ == VisualMode::kBoth;
  const SkinConfig& cfg = model_->config();
  const TaxelGrid& grid = cfg.grid;
  const int n = grid.n;
  const std::vector<double>& skin_z = model_->skin_z();
  const mjtNum* ppos = d->geom_xpos + 3 * pad_geom_;
  mjtNum turned[9];
  const mjtNum* pmat = PadFrameMat(d, pad_geom_, cfg.pad, turned);
  const double* ax = cfg.pad.semi_axes_m;
  const double top_z =  // pad frame: above the pad's far side
      (cfg.pad.rotated ? std::max({ax[0], ax[1], ax[2]}) : ax[2]) + kAboveGapM;
  auto to_world = [&](double x, double y, double z, mjtNum out[3]) {
    const mjtNum local[3] = {x, y, z};
    mju_mulMatVec3(out, pmat, local);
    mju_addTo3(out, ppos);
  };
  mjtNum pos[3], size[3];

  // The textures the skin feels, drawn when their group is hidden (their
  // group, 3 in mjtouch's scenes, is hidden by default): what the skin
  // touches is what the viewer shows, in any viewer. Once per geom, however
  // many skins feel it.
  for (int g : texture_geoms_) {
    if (opt->geomgroup[std::clamp(m->geom_group[g], 0, mjNGROUP - 1)]) continue;
    bool drawn = false;
    for (int k = 0; k < scn->ngeom && !drawn; ++k)
      drawn = scn->geoms[k].objtype == mjOBJ_GEOM && scn->geoms[k].objid == g;
    if (drawn) continue;
    if (!AddGeom(scn, m->geom_type[g], m->geom_size + 3 * g, d->geom_xpos + 3 * g,
                 d->geom_xmat + 9 * g, m->geom_rgba + 4 * g, sensor_id_))
      return;
    mjvGeom* copy = scn->geoms + scn->ngeom - 1;
    copy->objtype = mjOBJ_GEOM;  // the geom itself (segmentation, selection)
    copy->objid = g;
    copy->category = mjCAT_STATIC;
    copy->dataid = m->geom_type[g] == mjGEOM_MESH ? 2 * m->geom_dataid[g] : m->geom_dataid[g];
  }

  // Backing square of the `above` copy: the grid's extent, always shown.
  if (above) {
    size[0] = size[1] = grid.HalfExtent();
    size[2] = kTileHalfThickM;
    to_world(0, 0, top_z - 2 * kTileHalfThickM, pos);
    if (!AddGeom(scn, mjGEOM_BOX, size, pos, pmat, kBackingRgba, sensor_id_)) return;
    // The skin's ridge crests (where the relief peaks, s = k pitch across
    // the ridges) as thin lines over the square, so the heatmap's stripes
    // can be read against them.
    const Ridges& ridges = cfg.ridges;
    if (ridges.enabled && ridges.pitch_m > 0) {
      const double ca = std::cos(ridges.angle_rad), sa = std::sin(ridges.angle_rad);
      const double E = grid.HalfExtent();
      const double reach = E * (std::abs(ca) + std::abs(sa));
      for (int k = static_cast<int>(std::ceil(-reach / ridges.pitch_m));
           k * ridges.pitch_m <= reach; ++k) {
        const double s0 = k * ridges.pitch_m;
        // the crest {p : p . (ca, sa) = s0}, along (-sa, ca), clipped to [-E, E]^2
        double t_lo = -1e9, t_hi = 1e9;
        const double base[2] = {s0 * ca, s0 * sa}, dir[2] = {-sa, ca};
        bool empty = false;
        for (int a = 0; a < 2; ++a) {
          if (std::abs(dir[a]) < 1e-12) {
            empty = empty || std::abs(base[a]) > E;
            continue;
          }
          double t0 = (-E - base[a]) / dir[a], t1 = (E - base[a]) / dir[a];
          if (t0 > t1) std::swap(t0, t1);
          t_lo = std::max(t_lo, t0);
          t_hi = std::min(t_hi, t1);
        }
        if (empty || !(t_hi > t_lo)) continue;
        mjtNum from[3], to[3];
        const double z_line = top_z + 1.5 * kTileHalfThickM;  // just over the tiles
        to_world(base[0] + t_lo * dir[0], base[1] + t_lo * dir[1], z_line, from);
        to_world(base[0] + t_hi * dir[0], base[1] + t_hi * dir[1], z_line, to);
        if (!AddGeom(scn, mjGEOM_LINE, size, from, pmat, kRidgeRgba, sensor_id_)) return;
        mjv_connector(scn->geoms + scn->ngeom - 1, mjGEOM_LINE, kRidgeLineWidthPx, from, to);
      }
    }
  }

  // Heatmap: cell pressures averaged over b x b tiles.
  const std::vector<float>& pressure = workspace_.traction.pressure;
  if (touching_ && pressure.size() == grid.Size()) {
    const int b = (n + kMaxTilesPerSide - 1) / kMaxTilesPerSide;
    const int nt = (n + b - 1) / b;
    std::vector<double> mean(static_cast<size_t>(nt) * nt, 0.0);
    std::vector<double> lowest(mean.size(), std::numeric_limits<double>::infinity());
    std::vector<int> count(mean.size(), 0);
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const size_t c = static_cast<size_t>(j) * n + i;
        const size_t t = static_cast<size_t>(j / b) * nt + i / b;
        mean[t] += pressure[c];
        count[t]++;
        lowest[t] = std::min(lowest[t], skin_z[c]);
      }
    }
    double peak = 0;
    for (size_t t = 0; t < mean.size(); ++t) {
      mean[t] /= count[t];
      peak = std::max(peak, mean[t]);
    }
    if (peak > 0) {
      for (int tj = 0; tj < nt; ++tj) {
        for (int ti = 0; ti < nt; ++ti) {
          const size_t t = static_cast<size_t>(tj) * nt + ti;
          if (mean[t] < kMinRelPressure * peak) continue;
          const int i0 = ti * b, i1 = std::min(n, i0 + b), j0 = tj * b, j1 = std::min(n, j0 + b);
          const double x = 0.5 * (grid.Centre(i0) + grid.Centre(i1 - 1));
          const double y = 0.5 * (grid.Centre(j0) + grid.Centre(j1 - 1));
          float rgba[4];
          HeatColor(mean[t] / peak, rgba);
          size[0] = 0.5 * (i1 - i0) * grid.pitch_m * 0.95;
          size[1] = 0.5 * (j1 - j0) * grid.pitch_m * 0.95;
          size[2] = kTileHalfThickM;
          if (on_pad && std::isfinite(lowest[t])) {
            to_world(x, y, lowest[t] - kTileHalfThickM, pos);
            if (!AddGeom(scn, mjGEOM_BOX, size, pos, pmat, rgba, sensor_id_)) return;
          }
          if (above) {
            to_world(x, y, top_z, pos);
            if (!AddGeom(scn, mjGEOM_BOX, size, pos, pmat, rgba, sensor_id_)) return;
          }
        }
      }
    }
  }

  // Receptor sites: lit in their class colour for kFlashS after a spike.
  const auto& sites = model_->receptors();
  for (size_t r = 0; r < sites.size() && r < last_spike_time_s_.size(); ++r) {
    const ReceptorSite& s = sites[r];
    const double age = d->time - last_spike_time_s_[r];
    const bool lit = age >= 0 && age < kFlashS;
    const double radius = lit ? kLitRadiusM * (1.0 - 0.5 * age / kFlashS) : kIdleRadiusM;
    const float* rgba = lit ? kClassRgba[static_cast<int>(s.cls)] : kIdleRgba;
    size[0] = size[1] = size[2] = radius;
    const double z_skin = skin_z[static_cast<size_t>(s.j) * n + s.i];
    if (on_pad && std::isfinite(z_skin)) {
      to_world(s.x_m, s.y_m, z_skin - 2 * kTileHalfThickM - radius, pos);
      if (!AddGeom(scn, mjGEOM_SPHERE, size, pos, pmat, rgba, sensor_id_)) return;
    }
    if (above) {
      to_world(s.x_m, s.y_m, top_z + kTileHalfThickM + 0.5 * radius, pos);
      if (!AddGeom(scn, mjGEOM_SPHERE, size, pos, pmat, rgba, sensor_id_)) return;
    }
  }
}

}  // namespace mjtouch
