#include "surface/mesh_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numeric>

namespace mjtouch {

namespace {
constexpr int kLeafTriangles = 4;

// FNV-1a over raw bytes.
uint64_t Fnv1a(const void* data, size_t bytes, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; ++k) h = (h ^ p[k]) * 1099511628211ull;
  return h;
}
}  // namespace

std::shared_ptr<const PadMesh> MakePadMesh(const float* vertices, int nvert, const int* faces,
                                           int nface) {
  auto mesh = std::make_shared<PadMesh>();
  mesh->vertices_m.assign(vertices, vertices + 3 * static_cast<size_t>(nvert));
  mesh->faces.assign(faces, faces + 3 * static_cast<size_t>(nface));
  for (int v = 0; v < nvert; ++v) {
    const float* p = vertices + 3 * v;
    mesh->bound_radius_m =
        std::max(mesh->bound_radius_m,
                 std::sqrt(double(p[0]) * p[0] + double(p[1]) * p[1] + double(p[2]) * p[2]));
  }
  uint64_t h = 14695981039346656037ull;
  h = Fnv1a(mesh->vertices_m.data(), mesh->vertices_m.size() * sizeof(float), h);
  h = Fnv1a(mesh->faces.data(), mesh->faces.size() * sizeof(int), h);
  char key[64];
  std::snprintf(key, sizeof(key), "%d/%d/%016llx", nvert, nface,
                static_cast<unsigned long long>(h));
  mesh->key = key;
  mesh->caster = std::make_shared<MeshRayCaster>(vertices, nvert, faces, nface);
  return mesh;
}

MeshRayCaster::MeshRayCaster(const float* v, int nvert, const int* f, int nface) {
  tri_.reserve(static_cast<size_t>(nface) * 9);
  for (int t = 0; t < nface; ++t) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) ok = ok && f[3 * t + k] >= 0 && f[3 * t + k] < nvert;
    if (!ok) continue;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) tri_.push_back(v[3 * f[3 * t + k] + c]);
  }
  if (!tri_.empty()) Build(0, triangles());
}

// Median split of the triangles' centroids along the box's longest axis.
int MeshRayCaster::Build(int first, int count) {
  Node node;
  for (int c = 0; c < 3; ++c) {
    node.lo[c] = INFINITY;
    node.hi[c] = -INFINITY;
  }
  for (int t = first; t < first + count; ++t)
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        const float x = static_cast<float>(tri_[9 * t + 3 * k + c]);
        node.lo[c] = std::min(node.lo[c], std::nextafter(x, -INFINITY));
        node.hi[c] = std::max(node.hi[c], std::nextafter(x, INFINITY));
      }
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(node);
  if (count <= kLeafTriangles) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  int axis = 0;
  for (int c = 1; c < 3; ++c)
    if (node.hi[c] - node.lo[c] > node.hi[axis] - node.lo[axis]) axis = c;
  std::vector<int> order(count);
  std::iota(order.begin(), order.end(), first);
  auto centre = [&](int t) {
    return tri_[9 * t + axis] + tri_[9 * t + 3 + axis] + tri_[9 * t + 6 + axis];
  };
  const int half = count / 2;
  std::nth_element(order.begin(), order.begin() + half, order.end(),
                   [&](int a, int b) { return centre(a) < centre(b); });
  std::vector<double> sorted(static_cast<size_t>(count) * 9);
  for (int k = 0; k < count; ++k)
    std::copy_n(tri_.begin() + 9 * static_cast<size_t>(order[k]), 9, sorted.begin() + 9 * k);
  std::copy(sorted.begin(), sorted.end(), tri_.begin() + 9 * static_cast<size_t>(first));
  const int left = Build(first, half);
  const int right = Build(first + half, count - half);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

double MeshRayCaster::Cast(const double o[3], const double d[3]) const {
  if (nodes_.empty()) return -1.0;
  double inv[3];
  for (int c = 0; c < 3; ++c) inv[c] = 1.0 / d[c];  // +-inf on an axis-parallel ray
  double best = INFINITY;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    double t0 = 0.0, t1 = best;
    for (int c = 0; c < 3 && t0 <= t1; ++c) {
      double a = (n.lo[c] - o[c]) * inv[c], b = (n.hi[c] - o[c]) * inv[c];
      if (std::isnan(a) || std::isnan(b)) {  // 0 * inf: the ray lies in a slab face
        if (o[c] < n.lo[c] || o[c] > n.hi[c]) t0 = INFINITY;
        continue;
      }
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
    }
    if (t0 > t1) continue;
    if (n.left < 0) {
      for (int t = n.first; t < n.first + n.count; ++t) {
        // Moller-Trumbore, both sides
        const double* p = tri_.data() + 9 * static_cast<size_t>(t);
        const double e1[3] = {p[3] - p[0], p[4] - p[1], p[5] - p[2]};
        const double e2[3] = {p[6] - p[0], p[7] - p[1], p[8] - p[2]};
        const double q[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                             d[0] * e2[1] - d[1] * e2[0]};
        const double det = e1[0] * q[0] + e1[1] * q[1] + e1[2] * q[2];
        if (std::abs(det) < 1e-30) continue;
        const double inv_det = 1.0 / det;
        const double s[3] = {o[0] - p[0], o[1] - p[1], o[2] - p[2]};
        const double u = (s[0] * q[0] + s[1] * q[1] + s[2] * q[2]) * inv_det;
        if (u < 0.0 || u > 1.0) continue;
        const double r[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
                             s[0] * e1[1] - s[1] * e1[0]};
        const double v = (d[0] * r[0] + d[1] * r[1] + d[2] * r[2]) * inv_det;
        if (v < 0.0 || u + v > 1.0) continue;
        const double dist = (e2[0] * r[0] + e2[1] * r[1] + e2[2] * r[2]) * inv_det;
        if (dist >= 0.0 && dist < best) best = dist;
      }
    } else if (top + 2 <= 64) {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return std::isfinite(best) ? best : -1.0;
}

bool RayCellGap(const CounterSurface& s, const Pose& pad, double u, double v, double z, double h,
                int rays_per_side, double* gap_m, double* coverage) {
  if (!s.ray || rays_per_side < 1) return false;
  const double d_world[3] = {-pad.mat[2], -pad.mat[5], -pad.mat[8]};
  const int k = rays_per_side;
  const double step = h / k;
  double dist_sum = 0.0;
  int hits = 0;
  for (int a = 0; a < k; ++a) {
    const double x = u + (a + 0.5) * step - 0.5 * h;
    for (int b = 0; b < k; ++b) {
      const double y = v + (b + 0.5) * step - 0.5 * h;
      double o[3];
      for (int r = 0; r < 3; ++r)
        o[r] = pad.pos[r] + pad.mat[3 * r + 0] * x + pad.mat[3 * r + 1] * y;
      const double dist = s.ray(o, d_world);
      if (!(dist >= 0.0)) continue;
      dist_sum += dist;
      ++hits;
    }
  }
  if (hits == 0) return false;
  // dist is measured down from the pad's z = 0 plane: the top is at -dist.
  *gap_m = z + dist_sum / hits;
  *coverage = static_cast<double>(hits) / (k * k);
  return true;
}

}  // namespace mjtouch
