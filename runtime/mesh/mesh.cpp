#include "runtime/mesh/mesh.h"

#include <algorithm>
#include <cmath>

#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

double signed_volume(const Point3& a, const Point3& b, const Point3& c, const Point3& d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  return ((uy * vz - uz * vy) * wx + (uz * vx - ux * vz) * wy + (ux * vy - uy * vx) * wz) / 6.0;
}

double signed_volume(const Mesh& mesh, const Tetrahedron& t) {
  return signed_volume(mesh.points[static_cast<std::size_t>(t[0])], mesh.points[static_cast<std::size_t>(t[1])],
                       mesh.points[static_cast<std::size_t>(t[2])], mesh.points[static_cast<std::size_t>(t[3])]);
}

double triangle_area(const Point3& a, const Point3& b, const Point3& c) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  return 0.5 * std::sqrt(nx * nx + ny * ny + nz * nz);
}

double triangle_area(const Mesh& mesh, const Triangle& t) {
  return triangle_area(mesh.points[static_cast<std::size_t>(t[0])], mesh.points[static_cast<std::size_t>(t[1])],
                       mesh.points[static_cast<std::size_t>(t[2])]);
}

double squared_distance(const Point3& a, const Point3& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
  return dx * dx + dy * dy + dz * dz;
}

double distance(const Point3& a, const Point3& b) { return std::sqrt(squared_distance(a, b)); }

std::vector<Triangle> boundary_triangles(const Mesh& mesh, WorkerPool* given_pool) {
  PoolLease lease(given_pool, 0, mesh.points.size() + mesh.tetrahedra.size());
  WorkerPool& pool = lease.pool();
  // Faces of a positively oriented tetrahedron (a,b,c,d) with outward normals; face f of tetrahedron t is item
  // 4t + f. A face is grouped under its smallest vertex, and each group is sorted by (vertex set, item): a face met
  // once is on the boundary, kept as its tetrahedron orients it, in the order of the sorted vertex sets.
  const auto face = [&](std::size_t item) {
    const Tetrahedron& t = mesh.tetrahedra[item / 4];
    switch (item % 4) {
      case 0: return Triangle{t[0], t[2], t[1]};
      case 1: return Triangle{t[0], t[1], t[3]};
      case 2: return Triangle{t[1], t[2], t[3]};
      default: return Triangle{t[0], t[3], t[2]};
    }
  };
  const auto sorted = [](Triangle key) {
    std::sort(key.begin(), key.end());
    return key;
  };
  const KeyGroups groups = group_by_key(pool, mesh.points.size(), 4 * mesh.tetrahedra.size(),
                                        [&](std::size_t item, auto emit) {
                                          const Triangle f = face(item);
                                          emit(static_cast<std::size_t>(std::min({f[0], f[1], f[2]})));
                                        });
  std::vector<std::vector<Triangle>> found(pool.parts(mesh.points.size()));
  pool.run_parts(mesh.points.size(), [&](unsigned part, std::size_t first, std::size_t last) {
    std::vector<std::pair<Triangle, std::int32_t>> group;
    for (std::size_t v = first; v < last; ++v) {
      group.clear();
      for (auto g = groups.offset[v]; g < groups.offset[v + 1]; ++g) {
        const std::int32_t item = groups.item[static_cast<std::size_t>(g)];
        group.emplace_back(sorted(face(static_cast<std::size_t>(item))), item);
      }
      std::sort(group.begin(), group.end());
      for (std::size_t i = 0; i < group.size();) {
        std::size_t j = i + 1;
        while (j < group.size() && group[j].first == group[i].first) ++j;
        if (j - i == 1) found[part].push_back(face(static_cast<std::size_t>(group[i].second)));
        i = j;
      }
    }
  });
  std::vector<Triangle> boundary;
  for (const auto& part : found) boundary.insert(boundary.end(), part.begin(), part.end());
  return boundary;
}

}  // namespace fmpc::sim
