#include "runtime/meshing/tetgen_mesher.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <new>
#include <string>

// The Debian library is built with TETLIBRARY: errors throw an int instead of exiting.
#define TETLIBRARY
#include <tetgen.h>

namespace fmpc::sim {

namespace {

// TetGen's size callback is a plain function pointer with no user data: the field of the call in progress is held
// per thread (one meshing per thread at a time; TetGen itself is single-threaded).
thread_local const SizeField* current_size_field = nullptr;

// A tetrahedron is refined while its longest edge exceeds the field at its centroid.
bool tetrahedron_too_large(REAL* a, REAL* b, REAL* c, REAL* d, REAL*, REAL) {
  const Point3 p[4] = {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}, {c[0], c[1], c[2]}, {d[0], d[1], d[2]}};
  const Point3 centroid{(a[0] + b[0] + c[0] + d[0]) / 4.0, (a[1] + b[1] + c[1] + d[1]) / 4.0,
                        (a[2] + b[2] + c[2] + d[2]) / 4.0};
  const double h = size_at(*current_size_field, centroid);
  const double h2 = h * h;
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = i + 1; j < 4; ++j)
      if (squared_distance(p[i], p[j]) > h2) return true;
  return false;
}

class SizeFieldScope {
 public:
  explicit SizeFieldScope(const SizeField& field) { current_size_field = &field; }
  ~SizeFieldScope() { current_size_field = nullptr; }
  SizeFieldScope(const SizeFieldScope&) = delete;
  SizeFieldScope& operator=(const SizeFieldScope&) = delete;
};

// TetGen's exit codes (tetgen.h, terminatetetgen) as what the user can do about them.
std::string tetgen_failure(int code) {
  switch (code) {
    case 1:
      return "TetGen ran out of memory; use a larger size_far or size_near";
    case 3:
      return "TetGen found the surface intersecting itself; fix the surface (fmpc checks that it is closed, manifold "
             "and oriented, but not that it is free of self-intersections)";
    case 4:
      return "TetGen found an input feature smaller than its tolerance (1e-8 of the bounding box): two vertices or "
             "a vertex and an edge almost touch; clean the surface";
    case 5:
      return "TetGen found two surface triangles too close to each other (almost overlapping); clean the surface";
    case 10:
      return "TetGen refused the input; check that the surface is valid";
    default:
      return "TetGen failed with internal error " + std::to_string(code) + "; report it with the surface";
  }
}

// The surface as a piecewise linear complex: its points, and each triangle a facet of one polygon.
void fill_tetgen_input(const Mesh& surface, tetgenio& in) {
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.points.size());
  in.pointlist = new REAL[3 * surface.points.size()];
  for (std::size_t v = 0; v < surface.points.size(); ++v)
    for (std::size_t a = 0; a < 3; ++a) in.pointlist[3 * v + a] = surface.points[v][a];
  in.numberoffacets = static_cast<int>(surface.triangles.size());
  in.facetlist = new tetgenio::facet[surface.triangles.size()];
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    tetgenio::facet& facet = in.facetlist[t];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3];
    for (std::size_t k = 0; k < 3; ++k) facet.polygonlist[0].vertexlist[k] = surface.triangles[t][k];
  }
}

// TetGen is not thread-safe: its exact predicates keep their constants in globals, and its incremental Delaunay
// and point removal shuffle with the C library's srand() and rand(), seeded per call. Cohort patients are built on
// worker threads; interleaved, two meshings would draw from one another's sequence and differ from run to run.
// One call at a time in the process keeps every mesh the same.
std::mutex& tetgen_mutex() {
  static std::mutex mutex;
  return mutex;
}

// Runs TetGen with `switches`; false after an error naming what TetGen refused.
bool run_tetgen(const Mesh& surface, const char* switches, tetgenio& in, tetgenio& out, DiagnosticList& diagnostics) {
  tetgenbehavior behaviour;
  std::string copy(switches);
  if (!behaviour.parse_commandline(copy.data())) {
    diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                      "internal error: TetGen refused the switches '" + copy + "'");
    return false;
  }
  try {
    const std::lock_guard<std::mutex> lock(tetgen_mutex());
    tetrahedralize(&behaviour, &in, &out);
  } catch (int code) {
    diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0}, tetgen_failure(code));
    return false;
  } catch (const std::bad_alloc&) {
    diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0}, tetgen_failure(1));
    return false;
  }
  return true;
}

}  // namespace

bool tetgen_available() { return tetgen_termination_interposed(); }

std::optional<std::vector<std::size_t>> tetgen_self_intersections(const Mesh& surface, DiagnosticList& diagnostics) {
  tetgenio in;
  tetgenio out;
  fill_tetgen_input(surface, in);
  // p: the complex; d: detect self-intersections only (the intersecting triangles come back as trifaces); z, Q.
  if (!run_tetgen(surface, "pdzQ", in, out, diagnostics)) return std::nullopt;
  std::map<Triangle, std::size_t> index;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    Triangle key = surface.triangles[t];
    std::sort(key.begin(), key.end());
    index.emplace(key, t);
  }
  std::vector<std::size_t> found;
  for (int f = 0; f < out.numberoftrifaces; ++f) {
    Triangle key{out.trifacelist[3 * f], out.trifacelist[3 * f + 1], out.trifacelist[3 * f + 2]};
    std::sort(key.begin(), key.end());
    const auto it = index.find(key);
    if (it != index.end()) found.push_back(it->second);
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  return found;
}

std::optional<Mesh> tetgen_tetrahedralize(const Mesh& surface, const VolumeMeshOptions& options,
                                          std::size_t max_inserted, DiagnosticList& diagnostics) {
  tetgenio in;
  tetgenio out;
  fill_tetgen_input(surface, in);
  in.tetunsuitable = tetrahedron_too_large;
  // p: a piecewise linear complex; z: 0-based output; Q: quiet; q: radius-edge / dihedral bounds; S: the cap on
  // inserted vertices; Y: no vertex inserted on the surface (keep_surface).
  char switches[128];
  std::snprintf(switches, sizeof switches, "pzQq%.17g/%.17gS%zu%s", options.max_radius_edge_ratio,
                options.min_dihedral_degrees, max_inserted, options.keep_surface ? "Y" : "");
  SizeFieldScope scope(options.size);
  if (!run_tetgen(surface, switches, in, out, diagnostics)) return std::nullopt;
  if (out.numberofcorners != 4 || out.numberofpoints <= 0 || out.numberoftetrahedra <= 0) {
    diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                      "TetGen produced no tetrahedra; check that the surface encloses a volume");
    return std::nullopt;
  }
  Mesh mesh;
  mesh.source = surface.source;
  mesh.points.resize(static_cast<std::size_t>(out.numberofpoints));
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    mesh.points[v] = {out.pointlist[3 * v], out.pointlist[3 * v + 1], out.pointlist[3 * v + 2]};
  mesh.tetrahedra.resize(static_cast<std::size_t>(out.numberoftetrahedra));
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); ++t)
    for (std::size_t k = 0; k < 4; ++k) mesh.tetrahedra[t][k] = out.tetrahedronlist[4 * t + k];
  return mesh;
}

}  // namespace fmpc::sim
