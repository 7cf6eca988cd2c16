#include "skin_plugin.h"

#include "geom_names.h"
#include "pad_frame.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <shared_mutex>
#include <sstream>
#include <unordered_map>

#include "pipeline/text.h"

namespace mjtouch {
namespace {

std::string Config(const mjModel* m, int instance, const char* key) {
  const char* v = mj_getPluginConfig(m, instance, key);
  return v ? v : "";
}

void CopyPose(const mjtNum* pos, const mjtNum* mat, Pose* p) {
  for (int k = 0; k < 3; ++k) p->pos[k] = pos[k];
  for (int k = 0; k < 9; ++k) p->mat[k] = mat[k];
}

// A counter-surface for geom g facing the point `toward` (world). Planes,
// boxes, height fields, spheres, capsules, cylinders and ellipsoids are
// rendered from their exact geometry; meshes through ray queries of their
// triangles (`caster`, mesh_surface.h); anything else (sdf) by its tangent
// plane at the contact (pos, normal from the pad into the geom; null for a
// texture, which has no contact).
CounterSurface SurfaceForGeom(const mjModel* m, const mjData* d, int g, const mjtNum toward[3],
                              const mjtNum* contact_pos, const mjtNum* normal_into_geom,
                              const HeightFieldCache* cache, const MeshRayCaster* caster) {
  CounterSurface s;
  s.id = g;
  const mjtNum* gpos = d->geom_xpos + 3 * g;
  const mjtNum* gmat = d->geom_xmat + 9 * g;
  const mjtNum* size = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_PLANE:
      s.type = CounterSurface::Type::kPlane;
      CopyPose(gpos, gmat, &s.pose);
      return s;
    case mjGEOM_HFIELD: {
      const int h = m->geom_dataid[g];
      s.type = CounterSurface::Type::kHeightField;
      CopyPose(gpos, gmat, &s.pose);
      s.half_x_m = m->hfield_size[4 * h + 0];
      s.half_y_m = m->hfield_size[4 * h + 1];
      s.elevation_m = m->hfield_size[4 * h + 2];
      s.nrow = m->hfield_nrow[h];
      s.ncol = m->hfield_ncol[h];
      s.samples = m->hfield_data + m->hfield_adr[h];
      if (cache) {
        s.row_prefix = cache->prefix.data();
        s.rows_identical = cache->rows_identical;
        s.max_height_m = s.elevation_m * cache->max_sample;
      } else {
        s.max_height_m = s.elevation_m;  // samples are normalised to [0, 1]
      }
      return s;
    }
    case mjGEOM_BOX: {
      // A contact whose normal is off every face's (on an edge or corner):
      // the box as a body, whose top each cell's column meets. Else a face
      // (the aligned-face fast path for plates): the face whose outward
      // normal points most towards `toward`.
      mjtNum rel[3], loc[3];
      if (normal_into_geom) {
        mju_scl3(rel, normal_into_geom, -1);
        mju_mulMatTVec3(loc, gmat, rel);
        constexpr mjtNum kCos1Deg = 0.99984769515639124;
        if (!(std::max({std::abs(loc[0]), std::abs(loc[1]), std::abs(loc[2])}) > kCos1Deg)) {
          s.type = CounterSurface::Type::kBox;
          CopyPose(gpos, gmat, &s.pose);
          for (int k = 0; k < 3; ++k) s.size_m[k] = size[k];
          return s;
        }
      }
      mju_sub3(rel, toward, gpos);
      mju_mulMatTVec3(loc, gmat, rel);
      int axis = 0;
      mjtNum best = -1;
      for (int a = 0; a < 3; ++a) {
        const mjtNum score = std::abs(loc[a]) / size[a];
        if (score > best) {
          best = score;
          axis = a;
        }
      }
      const mjtNum sign = loc[axis] >= 0 ? 1 : -1;
      // Face frame columns (x', y', z') in box coordinates, right-handed,
      // z' = sign * e_axis.
      const int ax = (axis + 1) % 3, ay = (axis + 2) % 3;
      mjtNum F[9] = {0};  // row-major, columns are x', y', z'
      F[3 * ax + 0] = 1;
      F[3 * ay + 1] = sign;
      F[3 * axis + 2] = sign;
      mjtNum world[9];
      mju_mulMatMat(world, gmat, F, 3, 3, 3);
      mjtNum offset[3] = {0, 0, 0}, woff[3];
      offset[axis] = sign * size[axis];
      mju_mulMatVec3(woff, gmat, offset);
      s.type = CounterSurface::Type::kRectangle;
      for (int k = 0; k < 3; ++k) s.pose.pos[k] = gpos[k] + woff[k];
      for (int k = 0; k < 9; ++k) s.pose.mat[k] = world[k];
      s.half_x_m = size[ax];
      s.half_y_m = size[ay];
      return s;
    }
    case mjGEOM_SPHERE:
    case mjGEOM_CAPSULE:
    case mjGEOM_CYLINDER:
    case mjGEOM_ELLIPSOID:
      s.type = m->geom_type[g] == mjGEOM_SPHERE     ? CounterSurface::Type::kSphere
               : m->geom_type[g] == mjGEOM_CAPSULE  ? CounterSurface::Type::kCapsule
               : m->geom_type[g] == mjGEOM_CYLINDER ? CounterSurface::Type::kCylinder
                                                    : CounterSurface::Type::kEllipsoid;
      CopyPose(gpos, gmat, &s.pose);
      for (int k = 0; k < 3; ++k) s.size_m[k] = size[k];
      return s;
    case mjGEOM_MESH:
      s.type = CounterSurface::Type::kRay;
      CopyPose(gpos, gmat, &s.pose);
      s.bound_radius_m = m->geom_rbound[g];
      if (!caster) return s;  // no triangles: no ray hits
      // The ray in the mesh's frame (the geom's: MuJoCo stores mesh
      // vertices in it); distances are the same in both frames.
      s.ray = [caster, pose = s.pose](const double origin[3], const double dir[3]) {
        double o[3], v[3];
        for (int c = 0; c < 3; ++c) {
          o[c] = v[c] = 0.0;
          for (int r = 0; r < 3; ++r) {
            o[c] += pose.mat[3 * r + c] * (origin[r] - pose.pos[r]);
            v[c] += pose.mat[3 * r + c] * dir[r];
          }
        }
        return caster->Cast(o, v);
      };
      return s;
    default: {
      // Tangent plane: local z = -normal (outward from the geom, towards pad).
      mjtNum z[3] = {0, 0, 1};  // a texture has no contact (sdf textures are refused)
      if (normal_into_geom) mju_scl3(z, normal_into_geom, -1);
      mjtNum quat[4];
      mju_quatZ2Vec(quat, z);
      mjtNum mat[9];
      mju_quat2Mat(mat, quat);
      s.type = CounterSurface::Type::kPlane;
      CopyPose(contact_pos, mat, &s.pose);
      return s;
    }
  }
}

// Live plugins and the mjData each belongs to (see SkinPlugin::Owned).
// Never destroyed: an mjData may be freed after static destructors run.
// Shared for the per-step lookups (rollout threads do not serialise on it),
// exclusive to add, remove or reset.
std::shared_mutex& RegistryMutex() {
  static auto* mu = new std::shared_mutex();
  return *mu;
}
std::unordered_map<const SkinPlugin*, const mjData*>& Registry() {
  static auto* live = new std::unordered_map<const SkinPlugin*, const mjData*>();
  return *live;
}
// Bumped on every removal from the registry: a (plugin, mjData) pair found
// live stays live until then (a pointer is only re-added after removal).
std::atomic<unsigned long long>& RegistryGeneration() {
  static auto* generation = new std::atomic<unsigned long long>(0);
  return *generation;
}
// (plugin, mjData) pairs one thread found in the registry at a generation.
struct VerifiedPairs {
  static constexpr int kSize = 16;
  unsigned long long generation = ~0ull;
  const SkinPlugin* plugin[kSize];
  const mjData* data[kSize];
  int count = 0, next = 0;
};

// A non-finite sample in a height field the skin renders: a message naming
// the hfield, the geom and the first bad sample, or empty.
std::string CheckHeightFieldSamples(const mjModel* m, int geom) {
  const int h = m->geom_dataid[geom];
  const int nrow = m->hfield_nrow[h], ncol = m->hfield_ncol[h];
  const float* samples = m->hfield_data + m->hfield_adr[h];
  for (int r = 0; r < nrow; ++r)
    for (int c = 0; c < ncol; ++c) {
      const float v = samples[static_cast<size_t>(r) * ncol + c];
      if (std::isfinite(v)) continue;
      const char* hname = mj_id2name(m, mjOBJ_HFIELD, h);
      const char* gname = mj_id2name(m, mjOBJ_GEOM, geom);
      char buf[512];
      std::snprintf(buf, sizeof(buf),
                    "mjtouch.skin: height field '%s' (geom '%s') has sample %g at row %d, col %d "
                    "of %d x %d (mjModel.hfield_data); valid: finite (MuJoCo normalises "
                    "elevation to [0, 1])",
                    hname ? hname : "(unnamed)", gname ? gname : "(unnamed)", v, r, c, nrow, ncol);
      return buf;
    }
  return "";
}

std::string GeomMeshLabel(const mjModel* m, int g) {
  const char* gname = mj_id2name(m, mjOBJ_GEOM, g);
  const int id = m->geom_dataid[g];
  const char* mname = id >= 0 ? mj_id2name(m, mjOBJ_MESH, id) : nullptr;
  return Fmt("pad geom '%s' (mesh '%s')", gname ? gname : "(unnamed)", mname ? mname : "(unnamed)");
}

// Whether `samples` differ bitwise from the cache's copy at a spread of
// kHeightFieldSpread samples or in the block at cache->next_block (which
// then moves on): O(kHeightFieldSpread + kHeightFieldBlock) per call.
constexpr size_t kHeightFieldSpread = 256;
constexpr size_t kHeightFieldBlock = 4096;
bool HeightFieldChanged(const float* samples, HeightFieldCache* cache) {
  const float* copy = cache->samples.data();
  const size_t count = cache->samples.size();
  if (count == 0) return false;
  const size_t stride = std::max<size_t>(1, count / kHeightFieldSpread);
  for (size_t k = 0; k < count; k += stride)
    if (std::memcmp(samples + k, copy + k, sizeof(float)) != 0) return true;
  const size_t begin = cache->next_block < count ? cache->next_block : 0;
  const size_t n = std::min(kHeightFieldBlock, count - begin);
  cache->next_block = begin + n;
  return std::memcmp(samples + begin, copy + begin, n * sizeof(float)) != 0;
}

}  // namespace

// A mesh pad's surface: MuJoCo's convex hull of the mesh. MuJoCo collides a
// mesh geom as its hull, so its contacts lie on the hull: a dent the hull
// bridges is never touched there, and the skin must not put pressure on the
// dent's rim instead. Over a convex patch (most fingertips) hull and mesh are
// one surface. An open or non-manifold mesh is read as its hull too, as
// MuJoCo reads it.
bool SkinPlugin::ReadPadMesh(const mjModel* m, int g, PadGeometry* pad, std::string* error) {
  const int id = m->geom_dataid[g];
  const int graph = id >= 0 ? m->mesh_graphadr[id] : -1;
  if (graph < 0) {
    *error =
        Fmt("mjtouch.skin: %s has no convex hull: MuJoCo builds one only for a mesh geom "
            "that can collide (contype or conaffinity nonzero, or in a <pair>), and the skin "
            "reads the pad's surface from it; valid: a colliding pad geom",
            GeomMeshLabel(m, g).c_str());
    return false;
  }
  const int nvert = m->mesh_vertnum[id];
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[id];
  // mesh_graph: numvert, numface, vert_edgeadr, vert_globalid,
  // edge_localid (numvert + 3 numface), face_globalid (3 numface).
  const int* gr = m->mesh_graph + graph;
  const int hull_vert = gr[0], hull_face = gr[1];
  pad->mesh = MakePadMesh(vert, nvert, gr + 2 + 3 * hull_vert + 3 * hull_face, hull_face);
  pad->shape = PadShape::kMesh;
  for (int k = 0; k < 3; ++k) pad->semi_axes_m[k] = 0.0;
  for (int v = 0; v < nvert; ++v)
    for (int k = 0; k < 3; ++k)
      pad->semi_axes_m[k] = std::max<double>(pad->semi_axes_m[k], std::abs(vert[3 * v + k]));
  return true;
}

// `facing` of a mesh pad is in the geom's frame as written (the mesh file's
// axes): MuJoCo moves a mesh's vertices to its centre of mass and principal
// axes (mesh_pos, mesh_quat) and the compiled geom frame with them. The skin
// is centred on the line through the centre of mass along `facing`.
bool SkinPlugin::TurnMeshPad(const mjModel* m, int g, PadGeometry* pad, std::string* error) {
  const mjtNum* q = m->mesh_quat + 4 * m->geom_dataid[g];
  if (!(q[0] == 1 && q[1] == 0 && q[2] == 0 && q[3] == 0)) {
    mjtNum Rq[9], turned[9];
    mju_quat2Mat(Rq, q);
    mju_mulMatTMat(turned, Rq, pad->rotation, 3, 3, 3);
    std::copy(turned, turned + 9, pad->rotation);
    pad->rotated = true;
  }
  // The hull holds the centre of mass, so this line meets it unless the
  // hull is degenerate.
  const double* R = pad->rotation;
  const double d[3] = {R[2], R[5], R[8]};
  const double far = 2.0 * pad->mesh->bound_radius_m + 1e-3;
  const double start[3] = {-far * d[0], -far * d[1], -far * d[2]};
  if (!(pad->mesh->caster->Cast(start, d) >= 0.0)) {
    *error =
        Fmt("mjtouch.skin: %s: the line through its centre of mass along `facing` (%g %g %g in "
            "the compiled geom frame) meets no triangle of its hull; valid: a mesh enclosing a "
            "volume",
            GeomMeshLabel(m, g).c_str(), -d[0], -d[1], -d[2]);
    return false;
  }
  return true;
}

SkinPlugin* SkinPlugin::Owned(const mjData* d, int instance) {
  auto* p = reinterpret_cast<const SkinPlugin*>(d->plugin_data[instance]);
  if (!p) return nullptr;
  // The pairs this thread found live since the last removal: a step looks
  // its skins up without taking the registry lock.
  thread_local VerifiedPairs verified;
  const unsigned long long generation = RegistryGeneration().load(std::memory_order_acquire);
  if (verified.generation == generation) {
    for (int k = 0; k < verified.count; ++k)
      if (verified.plugin[k] == p && verified.data[k] == d) return const_cast<SkinPlugin*>(p);
  } else {
    verified.generation = generation;
    verified.count = verified.next = 0;
  }
  {
    std::shared_lock<std::shared_mutex> lock(RegistryMutex());
    auto it = Registry().find(p);
    if (it == Registry().end() || it->second != d) return nullptr;
  }
  verified.plugin[verified.next] = p;
  verified.data[verified.next] = d;
  verified.next = (verified.next + 1) % VerifiedPairs::kSize;
  verified.count =
      std::max(verified.count, verified.next == 0 ? VerifiedPairs::kSize : verified.next);
  return const_cast<SkinPlugin*>(p);
}

SkinPlugin* SkinPlugin::OwnedOrRebuilt(const mjModel* m, mjData* d, int instance) {
  if (SkinPlugin* p = Owned(d, instance)) return p;
  SkinPlugin* p = Create(m, d, instance);
  if (!p) return nullptr;
  {
    std::unique_lock<std::shared_mutex> lock(RegistryMutex());
    Registry()[p] = d;
  }
  // A pointer copied from elsewhere is not ours to free: overwrite it.
  d->plugin_data[instance] = reinterpret_cast<uintptr_t>(p);
  p->touching_ = d->plugin_state[m->plugin_stateadr[instance] + kStContactValid] > 0.0;
  p->last_spike_time_s_.assign(p->model_->receptors().size(),
                               -std::numeric_limits<double>::infinity());
  return p;
}

bool SkinPlugin::ParseConfig(const mjModel* m, int instance, SkinConfig* cfg, std::string* error) {
  return ParseSkinConfig([&](const char* key) { return Config(m, instance, key); }, cfg, error);
}

bool SkinPlugin::ReadConfig(const mjModel* m, int instance, SkinConfig* cfg, int* sensor_id,
                            int* pad_geom, std::string* error) {
  *sensor_id = -1;
  for (int i = 0; i < m->nsensor; ++i) {
    if (m->sensor_type[i] == mjSENS_PLUGIN && m->sensor_plugin[i] == instance) {
      *sensor_id = i;
      break;
    }
  }
  if (*sensor_id < 0) {
    *error = "mjtouch.skin: the plugin instance has no <sensor><plugin .../></sensor>";
    return false;
  }
  // MuJoCo lets several sensors name one instance, but a plugin computes one
  // sensor (the others would stay all zero).
  for (int i = *sensor_id + 1; i < m->nsensor; ++i) {
    if (m->sensor_type[i] == mjSENS_PLUGIN && m->sensor_plugin[i] == instance) {
      const char* iname = mj_id2name(m, mjOBJ_PLUGIN, instance);
      const char* a = mj_id2name(m, mjOBJ_SENSOR, *sensor_id);
      const char* b = mj_id2name(m, mjOBJ_SENSOR, i);
      *error = std::string("mjtouch.skin: plugin instance '") + (iname ? iname : "(unnamed)") +
               "' is used by two sensors, '" + (a ? a : "(unnamed)") + "' and '" +
               (b ? b : "(unnamed)") +
               "'; valid: one sensor per instance (give each sensor "
               "its own <instance>)";
      return false;
    }
  }
  if (m->sensor_objtype[*sensor_id] != mjOBJ_GEOM) {
    *error =
        "mjtouch.skin: the sensor must name the fingertip pad with objtype=\"geom\" "
        "objname=\"...\"";
    return false;
  }
  *pad_geom = m->sensor_objid[*sensor_id];
  const int g = *pad_geom;
  const mjtNum* size = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE:
      cfg->pad.shape = PadShape::kSphere;
      cfg->pad.semi_axes_m[0] = cfg->pad.semi_axes_m[1] = cfg->pad.semi_axes_m[2] = size[0];
      break;
    case mjGEOM_ELLIPSOID:
      cfg->pad.shape = PadShape::kEllipsoid;
      for (int k = 0; k < 3; ++k) cfg->pad.semi_axes_m[k] = size[k];
      break;
    case mjGEOM_CAPSULE:  // the -z end cap touches
      cfg->pad.shape = PadShape::kCapsule;
      cfg->pad.semi_axes_m[0] = cfg->pad.semi_axes_m[1] = size[0];
      cfg->pad.semi_axes_m[2] = size[0] + size[1];
      break;
    case mjGEOM_BOX:  // the -z face touches
      cfg->pad.shape = PadShape::kBox;
      for (int k = 0; k < 3; ++k) cfg->pad.semi_axes_m[k] = size[k];
      break;
    case mjGEOM_MESH:
      if (!ReadPadMesh(m, g, &cfg->pad, error)) return false;
      break;
    default: {
      const char* name = mj_id2name(m, mjOBJ_GEOM, g);
      *error = std::string("mjtouch.skin: pad geom '") + (name ? name : "?") +
               "' must be a sphere, ellipsoid, capsule, box or mesh";
      return false;
    }
  }
  if (!ParseConfig(m, instance, cfg, error)) return false;
  if (cfg->pad.shape == PadShape::kMesh && !TurnMeshPad(m, g, &cfg->pad, error)) return false;
  if (!FinalizeSkinConfig(cfg, error)) {
    if (cfg->pad.shape == PadShape::kMesh) {
      const char* name = mj_id2name(m, mjOBJ_GEOM, g);
      *error +=
          Fmt(" (pad geom '%s', a mesh: its footprint is the largest disc about the skin's "
              "centre inside the mesh's outline seen along `facing`, radius %g m)",
              name ? name : "(unnamed)", PadFootprintSemiAxis(cfg->pad));
    }
    return false;
  }
  ResolveOversample(cfg, m->opt.timestep);
  return true;
}

// The texture geoms (named by `texture`, and/or every non-colliding geom in
// `texture_group`) and the height fields the skin renders, checked.
bool SkinPlugin::ResolveTextures(const mjModel* m, int instance, const SkinConfig& cfg, int pad,
                                 std::vector<int>* textures, std::string* error) {
  textures->clear();
  // Texture geoms, rendered whenever the pad touches anything: named by
  // `texture`, and/or every non-colliding geom in `texture_group`.
  // Every geom type but sdf (no geometry the plugin can query), and not the
  // pad's own body.
  const int pad_body = m->body_weldid[m->geom_bodyid[pad]];
  auto renderable = [&](int g) { return m->geom_type[g] != mjGEOM_SDF; };
  auto on_pad = [&](int g) { return m->body_weldid[m->geom_bodyid[g]] == pad_body; };
  std::istringstream words(Config(m, instance, "texture"));
  const std::string pad_as_written = Config(m, instance, "pad_geom");
  const char* pad_name = mj_id2name(m, mjOBJ_GEOM, pad);
  if (!pad_as_written.empty() &&
      (!pad_name || std::string(pad_name).find(pad_as_written) == std::string::npos)) {
    *error =
        Fmt("mjtouch.skin: attribute `pad_geom` = '%s' is not part of the pad geom's name "
            "'%s'; valid: the pad's name as written, before MjSpec.attach's prefix and suffix",
            pad_as_written.c_str(), pad_name ? pad_name : "(unnamed)");
    return false;
  }
  std::string name;
  while (words >> name) {
    const int g = ResolveWrittenGeom(m, pad, pad_as_written, name);
    if (g < 0) {
      *error =
          Fmt("mjtouch.skin: attribute `texture` names geom '%s', which does not exist%s",
              name.c_str(), pad_as_written.empty() ? "" : " (with the pad's prefix and suffix)");
      return false;
    }
    if (!renderable(g)) {
      *error =
          Fmt("mjtouch.skin: attribute `texture` geom '%s' cannot be rendered against: an "
              "sdf geom; valid: plane, hfield, sphere, capsule, ellipsoid, cylinder, box, "
              "mesh",
              name.c_str());
      return false;
    }
    if (on_pad(g)) {
      *error =
          Fmt("mjtouch.skin: attribute `texture` geom '%s' cannot be rendered against: it "
              "moves with the pad (same body)",
              name.c_str());
      return false;
    }
    textures->push_back(g);
  }
  if (cfg.texture_group >= 0) {
    for (int g = 0; g < m->ngeom; ++g) {
      // Geoms on the pad's own body (e.g. its visual meshes) are not textures->
      if (m->geom_group[g] != cfg.texture_group || m->geom_contype[g] || m->geom_conaffinity[g] ||
          on_pad(g))
        continue;
      if (!renderable(g)) {
        const char* gname = mj_id2name(m, mjOBJ_GEOM, g);
        *error =
            Fmt("mjtouch.skin: geom '%s' in `texture_group` %d cannot be rendered against "
                "(an sdf geom; move it to another group)",
                gname ? gname : "(unnamed)", cfg.texture_group);
        return false;
      }
      if (std::find(textures->begin(), textures->end(), g) == textures->end())
        textures->push_back(g);
    }
  }
  // Height fields the skin renders (textures, and hfields that can collide
  // with the pad): a non-finite sample would silently drop the texture.
  auto may_collide = [&](int g) {
    if ((m->geom_contype[g] & m->geom_conaffinity[pad]) ||
        (m->geom_conaffinity[g] & m->geom_contype[pad]))
      return true;
    for (int k = 0; k < m->npair; ++k)
      if ((m->pair_geom1[k] == pad && m->pair_geom2[k] == g) ||
          (m->pair_geom2[k] == pad && m->pair_geom1[k] == g))
        return true;
    return false;
  };
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_type[g] != mjGEOM_HFIELD || on_pad(g)) continue;
    if (!may_collide(g) && std::find(textures->begin(), textures->end(), g) == textures->end())
      continue;
    const std::string bad = CheckHeightFieldSamples(m, g);
    if (!bad.empty()) {
      *error = bad;
      return false;
    }
  }
  return true;
}

// MuJoCo's compiler appends the warnings it collected to an init failure's
// error twice, after its own "plugin->init failed"; an error raised while it
// sizes the sensor reaches the user once, as the compile error. The sensor
// is linked to the instance only on the second sizing call: the pad and
// timestep checks run then.
bool SkinPlugin::CheckAtCompile(const mjModel* m, int instance, std::string* error) {
  SkinConfig cfg;
  if (!ParseConfig(m, instance, &cfg, error)) return false;
  bool linked = false;
  for (int i = 0; i < m->nsensor; ++i)
    linked = linked || (m->sensor_type[i] == mjSENS_PLUGIN && m->sensor_plugin[i] == instance);
  if (!linked) return true;
  int sensor_id, pad;
  cfg = SkinConfig();
  std::vector<int> textures;
  return ReadConfig(m, instance, &cfg, &sensor_id, &pad, error) &&
         CheckTactileRate(cfg, m->opt.timestep, error) &&
         ResolveTextures(m, instance, cfg, pad, &textures, error);
}

// About this many footprint cells a side (PatchShare): on a Shadow
// fingertip (a 7 mm capsule 24 mm long) under the rl grid, 36 of 1.1 mm.
constexpr int kFootprintCells = 32;

SkinPlugin* SkinPlugin::Create(const mjModel* m, mjData* d, int instance) {
  SkinConfig cfg;
  int sensor_id, pad;
  std::string error;
  if (!ReadConfig(m, instance, &cfg, &sensor_id, &pad, &error) ||
      !CheckTactileRate(cfg, m->opt.timestep, &error)) {
    mju_warning("%s", error.c_str());
    return nullptr;
  }
  std::vector<int> textures;
  if (!ResolveTextures(m, instance, cfg, pad, &textures, &error)) {
    mju_warning("%s", error.c_str());
    return nullptr;
  }
  auto model = SkinModel::Build(cfg, &error);
  if (!model) {
    mju_warning("%s", error.c_str());
    return nullptr;
  }
  if (model->output_size() != m->sensor_dim[sensor_id] ||
      model->state_size() != m->plugin_statenum[instance]) {
    mju_error("mjtouch.skin: internal error: layout changed between compile and init");
  }
  auto* p = new SkinPlugin();
  p->model_ = std::move(model);
  p->sensor_id_ = sensor_id;
  p->pad_geom_ = pad;
  p->pad_body_ = m->body_weldid[m->geom_bodyid[pad]];
  p->texture_geoms_ = std::move(textures);
  p->visual_ = cfg.visual;
  p->footprint_ = MakePatchFootprint(p->model_->config().grid, p->model_->skin_z(),
                                     p->model_->config().pad, kFootprintCells);
  return p;
}

void SkinPlugin::Reset(const mjModel* m, mjtNum* plugin_state, int instance) {
  ResetState(*model_, plugin_state);
  touching_ = false;
  last_spike_time_s_.assign(model_->receptors().size(), -std::numeric_limits<double>::infinity());
}

void SkinPlugin::GatherInput(const mjModel* m, const mjData* d) {
  StepInput& in = input_;
  in.timestep_s = m->opt.timestep;
  in.surfaces.clear();
  in.contacts.clear();
  in.in_contact = false;
  in.contact_normal_n = in.patch_normal_n = 0;
  const int pad = pad_geom_;
  const mjtNum* ppos = d->geom_xpos + 3 * pad;
  mjtNum turned[9];
  const mjtNum* pmat = PadFrameMat(d, pad, model_->config().pad, turned);
  CopyPose(ppos, pmat, &in.pad_pose);
  mjtNum total[3] = {0, 0, 0};
  // Coulomb's mu for shear="partial": the contacts' friction[0] weighted by
  // their normal forces (the plain mean if none pushes).
  double mu_weighted = 0, weight = 0, mu_sum = 0;
  int mu_count = 0;
  // One rule for what the skin feels and what `coverage` reports: a
  // contact facing the skin (FacesSkin) loads the patch by its share (1 or
  // PatchShare, below); the rest (the fingertip's side or back, past the
  // grid) is not felt, rather than forced onto the few patch cells its geom
  // reaches at the edge (an indentation of centimetres). Only geoms with a
  // share are rendered.
  contacts_.clear();
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if (c.exclude || c.efc_address < 0) continue;
    int other;
    if (c.geom[0] == pad)
      other = c.geom[1];
    else if (c.geom[1] == pad)
      other = c.geom[0];
    else
      continue;
    if (other < 0) continue;
    // mj_contactForce: contact frame (normal first); the normal points from
    // geom[0] to geom[1], so the force on geom[1] is +frame^T f.
    PadContact pc;
    pc.index = i;
    pc.other = other;
    mj_contactForce(m, d, i, pc.f_local);
    mju_mulMatTVec3(pc.f_world, c.frame, pc.f_local);
    pc.sign = (c.geom[1] == pad) ? 1 : -1;
    in.contact_normal_n += pc.f_local[0];
    pc.share = FacesSkin(c, pmat, -pc.sign) ? 1.0 : 0.0;
    contacts_.push_back(pc);
  }
  // A contact whose point lies over a covered taxel loads the patch whole
  // (the patch stands for the fingertip under it); one whose point lies off
  // it (a block along the fingertip, touching it past the grid) by the share
  // of its geom's overlap with the pad that lies on the patch.
  for (size_t a = 0; a < contacts_.size(); ++a) {
    const PadContact& first = contacts_[a];
    if (first.share == 0.0) continue;
    bool seen = false;
    for (size_t b = 0; b < a && !seen; ++b) seen = contacts_[b].other == first.other;
    if (seen) continue;
    const mjContact& c = d->contact[first.index];
    const mjtNum n_into[3] = {c.frame[0] * -first.sign, c.frame[1] * -first.sign,
                              c.frame[2] * -first.sign};  // from the pad into the other geom
    const HeightFieldCache* field = HeightField(m, first.other);
    if (field && field->bad) {
      for (size_t b = a; b < contacts_.size(); ++b)
        if (contacts_[b].other == first.other) contacts_[b].share = 0.0;
      continue;
    }
    const CounterSurface surface =
        SurfaceForGeom(m, d, first.other, ppos, c.pos, n_into, field, MeshCaster(m, first.other));
    std::optional<double> overlap_share;  // rendered on first need
    bool any = false;
    for (size_t b = a; b < contacts_.size(); ++b) {
      PadContact& pc = contacts_[b];
      if (pc.other != first.other || pc.share == 0.0) continue;
      pc.share = PointOnPatch(d->contact[pc.index].pos, pmat, ppos);
      if (pc.share == 0.0) {
        if (!overlap_share) overlap_share = PatchShare(&footprint_, in.pad_pose, surface);
        pc.share = std::max(*overlap_share, 0.0);
      }
      any = any || pc.share > 0.0;
    }
    if (any) in.surfaces.push_back(surface);
  }
  for (const PadContact& pc : contacts_) {
    if (!(pc.share > 0.0)) continue;
    const mjContact& c = d->contact[pc.index];
    const double share = pc.share;
    mjtNum f_world[3];
    mju_scl3(f_world, pc.f_world, share);
    in.patch_normal_n += share * pc.f_local[0];
    mju_addToScl3(total, f_world, pc.sign);
    in.in_contact = true;
    const double normal_n = std::max<double>(share * pc.f_local[0], 0.0);
    mu_weighted += normal_n * c.friction[0];
    weight += normal_n;
    mu_sum += c.friction[0];
    ++mu_count;
    {  // the contact in the pad frame, for the `contacts` pressure model
      mjtNum rel[3], loc[3], f_pad[3];
      mju_sub3(rel, c.pos, ppos);
      mju_mulMatTVec3(loc, pmat, rel);
      mju_scl3(f_world, f_world, pc.sign);
      mju_mulMatTVec3(f_pad, pmat, f_world);
      ContactPoint cp;
      cp.x_m = loc[0];
      cp.y_m = loc[1];
      for (int k = 0; k < 3; ++k) cp.force_n[k] = f_pad[k];
      in.contacts.push_back(cp);
    }
  }
  if (in.in_contact) {
    for (int g : texture_geoms_) {
      const HeightFieldCache* field = HeightField(m, g);
      if (field && field->bad) continue;
      in.surfaces.push_back(SurfaceForGeom(m, d, g, ppos, ppos, nullptr, field, MeshCaster(m, g)));
    }
  }
  in.friction_mu = weight > 0 ? mu_weighted / weight : mu_count > 0 ? mu_sum / mu_count : 0.0;
  // Force on the pad in the pad frame (columns of the row-major xmat).
  in.shear_x_n = total[0] * pmat[0] + total[1] * pmat[3] + total[2] * pmat[6];
  in.shear_y_n = total[0] * pmat[1] + total[1] * pmat[4] + total[2] * pmat[7];
  in.normal_force_n = total[0] * pmat[2] + total[1] * pmat[5] + total[2] * pmat[8];
}

bool SkinPlugin::FacesSkin(const mjContact& c, const mjtNum* pmat, mjtNum normal_sign) const {
  // The normal from the pad into the other geom within 45 degrees of the
  // skin's outward -z. Beyond, the contact pushes the fingertip more
  // sideways than into the skin (a neighbouring finger on its side): the
  // skin, pressed along its z, would take it on the few steep cells at the
  // grid's edge. The render keeps to the same patch: a body indents a cell
  // only where it crosses the skin's surface along the cell's column
  // (surface/render.cc).
  constexpr mjtNum kCos45 = 0.70710678118654752;
  const mjtNum n_z =
      normal_sign * (c.frame[0] * pmat[2] + c.frame[1] * pmat[5] + c.frame[2] * pmat[8]);
  return n_z < -kCos45;
}

double SkinPlugin::PointOnPatch(const mjtNum* pos, const mjtNum* pmat, const mjtNum* ppos) const {
  mjtNum rel[3], loc[3];
  mju_sub3(rel, pos, ppos);
  mju_mulMatTVec3(loc, pmat, rel);
  const TaxelGrid& grid = model_->config().grid;
  // Any covered cell within half a pitch of the point: MuJoCo puts a flat
  // face's contacts on its corners, on the covered cells' outline.
  const double h = grid.pitch_m, half = 0.5 * grid.n * h;
  auto cells = [&](double x, int* c0, int* c1) {
    if (!(std::abs(x) < half + 0.5 * h)) return false;
    *c0 = std::max(0, static_cast<int>(std::floor((x + half) / h - 0.5)));
    *c1 = std::min(grid.n - 1, static_cast<int>(std::floor((x + half) / h + 0.5)));
    return *c0 <= *c1;
  };
  int i0, i1, j0, j1;
  if (!cells(loc[0], &i0, &i1) || !cells(loc[1], &j0, &j1)) return 0.0;
  const std::vector<double>& z = model_->skin_z();
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i)
      if (std::isfinite(z[static_cast<size_t>(j) * grid.n + i])) return 1.0;
  return 0.0;
}

void SkinPlugin::WarnOffPatch(const mjModel* m) {
  const StepInput& in = input_;
  if (warned_off_patch_ || !(in.contact_normal_n > 0.0) ||
      !(in.patch_normal_n < (1.0 - 1e-6) * in.contact_normal_n))
    return;
  warned_off_patch_ = true;
  const char* sensor = mj_id2name(m, mjOBJ_SENSOR, sensor_id_);
  const char* geom = mj_id2name(m, mjOBJ_GEOM, pad_geom_);
  mju_warning(
      "mjtouch.skin '%s': %.3g of MuJoCo's %.3g N normal force on pad geom '%s' lands "
      "off the skin's patch (past the nx x pitch grid, or on the geom's side or back) "
      "and is not felt; enable the `coverage` output to follow it, widen the grid or "
      "turn the skin with `facing` (warned once)",
      sensor ? sensor : "(unnamed)", in.contact_normal_n - in.patch_normal_n, in.contact_normal_n,
      geom ? geom : "(unnamed)");
}

const MeshRayCaster* SkinPlugin::MeshCaster(const mjModel* m, int geom) {
  if (m->geom_type[geom] != mjGEOM_MESH) return nullptr;
  const int id = m->geom_dataid[geom];
  if (id < 0) return nullptr;
  auto it = meshes_.find(id);
  if (it == meshes_.end()) {
    it = meshes_
             .emplace(id, std::make_unique<MeshRayCaster>(
                              m->mesh_vert + 3 * m->mesh_vertadr[id], m->mesh_vertnum[id],
                              m->mesh_face + 3 * m->mesh_faceadr[id], m->mesh_facenum[id]))
             .first;
  }
  return it->second.get();
}

const HeightFieldCache* SkinPlugin::HeightField(const mjModel* m, int geom) {
  if (m->geom_type[geom] != mjGEOM_HFIELD) return nullptr;
  const int h = m->geom_dataid[geom];
  const int nrow = m->hfield_nrow[h], ncol = m->hfield_ncol[h];
  const float* samples = m->hfield_data + m->hfield_adr[h];
  const size_t count = static_cast<size_t>(nrow) * ncol;
  auto it = hfields_.find(h);
  // mjModel.hfield_data may be edited while the model runs: the cache
  // follows the samples. A full comparison each use would cost as much as
  // the field is large, so each use compares a spread of samples and one
  // block that moves on every use (every sample is compared within
  // count / kHeightFieldBlock uses); a difference rebuilds the cache.
  if (it != hfields_.end() && it->second.samples.size() == count &&
      !HeightFieldChanged(samples, &it->second))
    return &it->second;
  HeightFieldCache& c = hfields_[h];
  c.samples.assign(samples, samples + count);
  c.next_block = 0;
  const std::string bad = CheckHeightFieldSamples(m, geom);
  c.bad = !bad.empty();
  if (c.bad) {
    // Checked at init; an edit since: warned once, the field left out.
    if (!warned_height_field_)
      mju_warning(
          "%s; it was edited after the MjData was made: the skin leaves this height "
          "field out until its samples are finite (warned once)",
          bad.c_str());
    warned_height_field_ = true;
    return &c;
  }
  c.prefix = HeightFieldRowPrefix(nrow, ncol, samples);
  c.max_sample = 0;
  for (size_t k = 0; k < count; ++k) c.max_sample = std::max<double>(c.max_sample, samples[k]);
  c.rows_identical = true;
  for (int r = 1; r < nrow && c.rows_identical; ++r)
    c.rows_identical = std::equal(samples, samples + ncol, samples + static_cast<size_t>(r) * ncol);
  return &c;
}

// Warnings of the run, each once per MjData: the force block's last column
// flags every step past the skin.
void SkinPlugin::WarnOnce(const mjModel* m, const double* state) {
  if (!warned_beyond_skin_ && IndentationBeyondSkin(*model_, state)) {
    warned_beyond_skin_ = true;
    const SkinConfig& cfg = model_->config();
    const bool stack = cfg.layered && cfg.base.rigid;
    mju_warning(
        "mjtouch.skin: the indentation %g m at time %g s exceeds %s (%g m): the linear "
        "skin is past its range there (the bone or the pad would carry the load); the "
        "force block's last column flags such steps (warned once)",
        state[kStContactDepth], state[kStLastTime],
        stack ? "the skin stack over the rigid base" : "the pad's half-height",
        IndentationLimit(cfg));
  }
}

void SkinPlugin::Compute(const mjModel* m, mjData* d, int instance) {
  GatherInput(m, d);
  WarnOffPatch(m);
  mjtNum* state = d->plugin_state + m->plugin_stateadr[instance];
  mjtNum* out = d->sensordata + m->sensor_adr[sensor_id_];
  const int fired = Step(*model_, input_, d->time, state, &workspace_, out);
  WarnOnce(m, state);
  // For drawing only: whether the field is live, and when each receptor last fired.
  touching_ = state[kStContactValid] > 0.0;
  if (fired > 0) {
    const std::vector<double>& spikes = workspace_.spikes;
    for (size_t r = 0; r < last_spike_time_s_.size(); ++r)
      if (spikes[r] > 0) last_spike_time_s_[r] = d->time;
  }
}

void SkinPlugin::RegisterPlugin() {
  mjpPlugin plugin;
  mjp_defaultPlugin(&plugin);
  plugin.name = kName;
  plugin.capabilityflags |= mjPLUGIN_SENSOR;
  const auto& keys = SkinAttributeKeys();
  plugin.nattribute = static_cast<int>(keys.size());
  plugin.attributes = keys.data();
  // Contact forces are known only after the constraint solver. MuJoCo then
  // also runs mj_rnePostConstraint (body accelerations) once per step before
  // any acceleration-stage plugin sensor, which the skin does not read; no
  // earlier stage has the forces.
  plugin.needstage = mjSTAGE_ACC;

  plugin.nstate = +[](const mjModel* m, int instance) {
    SkinConfig cfg;
    std::string error;
    if (!ParseConfig(m, instance, &cfg, &error)) return 0;
    return SkinModel::StateSize(cfg, static_cast<int>(SkinModel::PlaceReceptors(cfg).size()));
  };
  plugin.nsensordata = +[](const mjModel* m, int instance, int sensor_id) {
    SkinConfig cfg;
    std::string error;
    // On a line of its own, after MuJoCo's "engine error: ".
    if (!CheckAtCompile(m, instance, &error)) mju_error("\n%s", error.c_str());
    if (!ParseConfig(m, instance, &cfg, &error)) return 0;
    return SkinModel::OutputSize(cfg, static_cast<int>(SkinModel::PlaceReceptors(cfg).size()));
  };
  plugin.init = +[](const mjModel* m, mjData* d, int instance) {
    SkinPlugin* p = SkinPlugin::Create(m, d, instance);
    if (!p) return -1;
    {
      std::unique_lock<std::shared_mutex> lock(RegistryMutex());
      Registry()[p] = d;
    }
    d->plugin_data[instance] = reinterpret_cast<uintptr_t>(p);
    p->Reset(m, d->plugin_state + m->plugin_stateadr[instance], instance);
    return 0;
  };
  plugin.destroy = +[](mjData* d, int instance) {
    // Only the owner frees (an unpickled mjData shares or dangles its copy).
    if (SkinPlugin* p = Owned(d, instance)) {
      {
        std::unique_lock<std::shared_mutex> lock(RegistryMutex());
        Registry().erase(p);
        RegistryGeneration().fetch_add(1, std::memory_order_release);
      }
      delete p;
    }
    d->plugin_data[instance] = 0;
  };
  // Each MjData owns its scratch; the shared SkinModel is reference counted.
  plugin.copy = +[](mjData* dest, const mjModel* m, const mjData* src, int instance) {
    const SkinPlugin* from = Owned(src, instance);
    SkinPlugin* to = OwnedOrRebuilt(m, dest, instance);
    if (from && to && from != to) {
      to->input_ = from->input_;
      to->workspace_ = from->workspace_;
      to->touching_ = from->touching_;
      to->last_spike_time_s_ = from->last_spike_time_s_;
    }
  };
  plugin.reset = +[](const mjModel* m, mjtNum* plugin_state, void* plugin_data, int instance) {
    // No mjData here: a live plugin (any owner; its drawing state is reset
    // too) or, for a pointer copied from another process, the model's own.
    auto* p = static_cast<SkinPlugin*>(plugin_data);
    {
      std::unique_lock<std::shared_mutex> lock(RegistryMutex());
      if (p && Registry().count(p)) {
        p->Reset(m, plugin_state, instance);
        return;
      }
    }
    SkinConfig cfg;
    int sensor_id, pad;
    std::string error;
    if (!plugin_data || !ReadConfig(m, instance, &cfg, &sensor_id, &pad, &error)) return;
    if (auto model = SkinModel::Build(cfg, &error)) ResetState(*model, plugin_state);
  };
  plugin.compute = +[](const mjModel* m, mjData* d, int instance, int capability_bit) {
    if (SkinPlugin* p = OwnedOrRebuilt(m, d, instance)) p->Compute(m, d, instance);
  };
  plugin.visualize =
      +[](const mjModel* m, mjData* d, const mjvOption* opt, mjvScene* scn, int instance) {
        if (const SkinPlugin* p = OwnedOrRebuilt(m, d, instance))
          p->Visualize(m, d, opt, scn, instance);
      };
  mjp_registerPlugin(&plugin);
}

}  // namespace mjtouch
