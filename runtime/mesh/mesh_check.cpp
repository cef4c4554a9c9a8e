#include "runtime/mesh/mesh_check.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

const char* to_string(MeshFindingKind kind) {
  switch (kind) {
    case MeshFindingKind::IndexOutOfRange:
      return "index-out-of-range";
    case MeshFindingKind::DegenerateTetrahedron:
      return "degenerate-tetrahedron";
    case MeshFindingKind::InvertedTetrahedron:
      return "inverted-tetrahedron";
    case MeshFindingKind::DuplicateTetrahedron:
      return "duplicate-tetrahedron";
    case MeshFindingKind::DegenerateTriangle:
      return "degenerate-triangle";
    case MeshFindingKind::DuplicateTriangle:
      return "duplicate-triangle";
    case MeshFindingKind::DuplicateVertex:
      return "duplicate-vertex";
    case MeshFindingKind::UnreferencedVertex:
      return "unreferenced-vertex";
  }
  return "unknown";
}

namespace {

template <std::size_t N>
bool indices_in_range(const std::array<std::int32_t, N>& element, std::size_t vertex_count) {
  return std::all_of(element.begin(), element.end(),
                     [&](std::int32_t v) { return v >= 0 && static_cast<std::size_t>(v) < vertex_count; });
}

template <std::size_t N>
bool has_repeated_vertex(const std::array<std::int32_t, N>& element) {
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = i + 1; j < N; ++j) {
      if (element[i] == element[j]) return true;
    }
  }
  return false;
}

// The largest of the element's edge lengths. sqrt is correctly rounded, hence monotonic: the square root of the
// largest squared length is the largest distance(), bit for bit, with one square root instead of N(N-1)/2.
template <std::size_t N>
double longest_edge(const Mesh& mesh, const std::array<std::int32_t, N>& element) {
  double longest_squared = 0.0;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = i + 1; j < N; ++j) {
      longest_squared = std::max(longest_squared, squared_distance(mesh.points[static_cast<std::size_t>(element[i])],
                                                                   mesh.points[static_cast<std::size_t>(element[j])]));
    }
  }
  return std::sqrt(longest_squared);
}

int line_of(const std::vector<int>& lines, std::size_t index) { return index < lines.size() ? lines[index] : 0; }

PoolLease check_pool(const Mesh& mesh, const MeshCheckOptions& options, WorkerPool* given) {
  return PoolLease(given, options.threads, mesh.points.size() + mesh.tetrahedra.size() + mesh.triangles.size());
}

double duplicate_tolerance(const Mesh& mesh, const MeshCheckOptions& options) {
  if (options.duplicate_distance >= 0.0) return options.duplicate_distance;
  Point3 low{0.0, 0.0, 0.0}, high{0.0, 0.0, 0.0};
  bool any = false;
  for (const Point3& p : mesh.points) {
    if (!finite_point(p)) continue;  // such a vertex is never a duplicate (its distances are NaN or infinite)
    if (!any) low = high = p;
    any = true;
    for (std::size_t a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], p[a]);
      high[a] = std::max(high[a], p[a]);
    }
  }
  return any ? 1e-9 * distance(low, high) : 0.0;
}

struct SortedPoint {
  double x, y, z;
  std::size_t index;
};

bool operator<(const SortedPoint& a, const SortedPoint& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  if (a.z != b.z) return a.z < b.z;
  return a.index < b.index;
}

// The first position in (from, end) where `reached` holds, given that it holds from there on (a monotonic
// predicate): galloping, so a short jump costs a few comparisons and a long one a logarithm.
template <class Reached>
std::size_t first_reached(std::size_t from, std::size_t end, const Reached& reached) {
  std::size_t low = from, step = 1;  // reached(low) is false
  std::size_t high = from + 1;
  while (high < end && !reached(high)) {
    low = high;
    step *= 2;
    high = std::min(end, high + step);
  }
  // reached(high) or high == end; reached(low) is false.
  while (high - low > 1) {
    const std::size_t mid = low + (high - low) / 2;
    if (reached(mid))
      high = mid;
    else
      low = mid;
  }
  return high;
}

// The pairs (s, t), s < t, of sorted positions whose points are within `tolerance`, for s in [begin, end), in
// increasing (s, t): the pairs the sweep over the points sorted by (x, y, z, index) meets. visit(s, t) returns
// false to stop early (then the scan returns false).
//
// For each s the band is the t with x_t - x_s <= tolerance (x is sorted). Inside it the points are sorted by y
// within each run of equal x, and by z within each run of equal (x, y), so the scan jumps over the points whose y
// (or z) differs by more than `margin`. margin is tolerance widened by more than distance()'s rounding and floored
// above the squares' underflow (2^-500), so a skipped point is never within tolerance: the pairs are exactly
// those of the plain sweep that tests every point in the band.
template <class Visit>
bool scan_close_pairs(const std::vector<SortedPoint>& sorted, std::size_t begin, std::size_t end, double tolerance,
                      const Visit& visit) {
  const double margin = std::max(tolerance * (1.0 + 1e-12), 1e-150);
  const std::size_t n = sorted.size();
  for (std::size_t s = begin; s < end; ++s) {
    const SortedPoint& p = sorted[s];
    const std::size_t band_end =
        first_reached(s, n, [&](std::size_t t) { return !(sorted[t].x - p.x <= tolerance); });
    std::size_t t = s + 1;
    while (t < band_end) {
      const SortedPoint& q = sorted[t];
      const double dy = q.y - p.y;
      if (dy > margin) {  // the rest of this x run is further in y
        t = first_reached(t, band_end, [&](std::size_t u) { return sorted[u].x != q.x; });
        continue;
      }
      if (dy < -margin) {
        t = first_reached(t, band_end,
                          [&](std::size_t u) { return sorted[u].x != q.x || !(sorted[u].y - p.y < -margin); });
        continue;
      }
      const double dz = q.z - p.z;
      if (dz > margin) {
        t = first_reached(t, band_end, [&](std::size_t u) { return sorted[u].x != q.x || sorted[u].y != q.y; });
        continue;
      }
      if (dz < -margin) {
        t = first_reached(t, band_end, [&](std::size_t u) {
          return sorted[u].x != q.x || sorted[u].y != q.y || !(sorted[u].z - p.z < -margin);
        });
        continue;
      }
      if (distance({p.x, p.y, p.z}, {q.x, q.y, q.z}) <= tolerance && !visit(s, t)) return false;
      ++t;
    }
  }
  return true;
}

// For each vertex, the earliest vertex within `tolerance` (itself when none), as the sweep over the vertices
// sorted by (x, y, z, index) defines it: every close pair (i, j), in sweep order, points the later of the two at
// the earlier representative of both; then chains (c near b near a) are resolved to their earliest member. The
// close pairs are found in parallel (scan_close_pairs) and applied in sweep order, so the result is the sweep's.
// Vertices with a non-finite coordinate are never duplicates.
std::vector<std::size_t> duplicate_representatives(const Mesh& mesh, double tolerance, WorkerPool& pool) {
  const std::size_t n = mesh.points.size();
  std::vector<std::size_t> representative;
  resize_large(representative, n);
  pool.run(n, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) representative[v] = v;
  });
  std::vector<SortedPoint> sorted;
  {
    const unsigned parts = pool.parts(n);
    std::vector<std::size_t> finite(parts + 1, 0);
    pool.run_parts(n, [&](unsigned part, std::size_t begin, std::size_t end) {
      for (std::size_t v = begin; v < end; ++v) finite[part + 1] += finite_point(mesh.points[v]) ? 1 : 0;
    });
    for (unsigned p = 0; p < parts; ++p) finite[p + 1] += finite[p];
    resize_large(sorted, finite[parts]);
    pool.run_parts(n, [&](unsigned part, std::size_t begin, std::size_t end) {
      std::size_t next = finite[part];
      for (std::size_t v = begin; v < end; ++v) {
        const Point3& p = mesh.points[v];
        if (finite_point(p)) sorted[next++] = {p[0], p[1], p[2], v};
      }
    });
  }
  parallel_sort(pool, sorted, [](const SortedPoint& a, const SortedPoint& b) { return a < b; });

  const auto apply = [&](std::size_t s, std::size_t t) {
    const std::size_t i = sorted[s].index, j = sorted[t].index;
    const std::size_t first = std::min(representative[i], representative[j]);
    const std::size_t later = std::max(i, j);
    if (first < representative[later]) representative[later] = first;
    return true;
  };
  // Each part keeps up to two pairs per point (real duplicates are few); a part that has more (a huge tolerance,
  // many coincident points) is scanned again below while its pairs are applied, in the same order, unstored.
  const unsigned parts = pool.parts(sorted.size());
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> pairs(parts);
  std::vector<char> overflowed(parts, 0);
  pool.run_parts(sorted.size(), [&](unsigned part, std::size_t begin, std::size_t end) {
    std::vector<std::pair<std::size_t, std::size_t>>& mine = pairs[part];
    const std::size_t cap = 2 * (end - begin) + 1024;
    const bool complete = scan_close_pairs(sorted, begin, end, tolerance, [&](std::size_t s, std::size_t t) {
      mine.emplace_back(s, t);
      return mine.size() < cap;
    });
    if (!complete) {
      overflowed[part] = 1;
      std::vector<std::pair<std::size_t, std::size_t>>().swap(mine);
    }
  });
  for (unsigned part = 0; part < parts; ++part) {
    if (overflowed[part]) {
      const auto [begin, end] = chunk_range(sorted.size(), parts, part);
      scan_close_pairs(sorted, begin, end, tolerance, apply);
    } else {
      for (const auto& [s, t] : pairs[part]) apply(s, t);
    }
  }
  for (std::size_t v = 0; v < n; ++v) representative[v] = representative[representative[v]];
  return representative;
}

// What check_elements finds about one element before looking for duplicates: whether it takes part in the
// duplicate search (indices in range, not degenerate), and the finding about its indices or shape, if any.
struct ShapeVerdict {
  bool has_finding = false;
  bool keyed = false;
  MeshFinding finding;
};

template <std::size_t N>
double element_measure(const Mesh& mesh, const std::array<std::int32_t, N>& element) {
  if constexpr (N == 4)
    return signed_volume(mesh, element);
  else
    return triangle_area(mesh, element);
}

template <std::size_t N>
ShapeVerdict check_shape(const Mesh& mesh, const std::array<std::int32_t, N>& element, std::size_t e,
                         const std::vector<int>& lines, const MeshCheckOptions& options) {
  constexpr bool tetrahedra = N == 4;
  ShapeVerdict verdict;
  MeshFinding& finding = verdict.finding;
  finding.index = e;
  finding.line = line_of(lines, e);
  if (!indices_in_range(element, mesh.points.size())) {
    finding.kind = MeshFindingKind::IndexOutOfRange;
    verdict.has_finding = true;
    return verdict;
  }
  const double measure = element_measure(mesh, element);
  double scale = longest_edge(mesh, element);
  scale = tetrahedra ? scale * scale * scale : scale * scale;
  finding.value = measure;
  if (has_repeated_vertex(element) || std::abs(measure) <= options.shape_tolerance * scale) {
    finding.kind = tetrahedra ? MeshFindingKind::DegenerateTetrahedron : MeshFindingKind::DegenerateTriangle;
    verdict.has_finding = true;
    return verdict;
  }
  verdict.keyed = true;
  if (tetrahedra && measure < 0.0) {
    finding.kind = MeshFindingKind::InvertedTetrahedron;
    verdict.has_finding = true;
  }
  return verdict;
}

// Every element's verdict: the findings about indices and shapes (in element order) and the keyed flags.
template <std::size_t N>
std::vector<MeshFinding> check_shapes(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                                      const std::vector<int>& lines, const MeshCheckOptions& options,
                                      WorkerPool& pool, std::vector<std::uint8_t>* keyed) {
  const std::size_t count = elements.size();
  if (keyed) resize_large(*keyed, count);
  std::vector<std::vector<MeshFinding>> found(pool.parts(count));
  pool.run_parts(count, [&](unsigned part, std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      const ShapeVerdict verdict = check_shape(mesh, elements[e], e, lines, options);
      if (keyed) (*keyed)[e] = verdict.keyed ? 1 : 0;
      if (verdict.has_finding) found[part].push_back(verdict.finding);
    }
  });
  std::vector<MeshFinding> findings;
  for (auto& part : found) findings.insert(findings.end(), part.begin(), part.end());
  return findings;
}

// The findings of one element array in element order: index out of range, degenerate, inverted (tetrahedra), and
// duplicate (the same vertex set as the earliest keyed element with it), an inverted element's duplicate finding
// after its inverted one. Duplicates share their smallest vertex: the keyed elements are grouped by it and each
// group is sorted by (vertex set, element).
template <std::size_t N>
void check_elements(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                    const std::vector<int>& lines, const MeshCheckOptions& options, WorkerPool& pool,
                    std::vector<MeshFinding>& findings) {
  constexpr bool tetrahedra = N == 4;
  using Key = std::array<std::int32_t, N>;
  std::vector<std::uint8_t> keyed;
  const std::vector<MeshFinding> shapes = check_shapes(mesh, elements, lines, options, pool, &keyed);
  const auto sorted_key = [&](std::size_t e) {
    Key key = elements[e];
    std::sort(key.begin(), key.end());
    return key;
  };
  std::vector<std::pair<std::size_t, std::size_t>> duplicates;  // (element, earlier element with its vertex set)
  {
    const KeyGroups groups = group_by_key(pool, mesh.points.size(), elements.size(), [&](std::size_t e, auto emit) {
      if (keyed[e]) emit(static_cast<std::size_t>(*std::min_element(elements[e].begin(), elements[e].end())));
    });
    keyed = std::vector<std::uint8_t>();
    std::vector<std::vector<std::pair<std::size_t, std::size_t>>> found(pool.parts(mesh.points.size()));
    pool.run_parts(mesh.points.size(), [&](unsigned part, std::size_t begin, std::size_t end) {
      std::vector<std::pair<Key, std::size_t>> group;
      for (std::size_t v = begin; v < end; ++v) {
        const auto first = static_cast<std::size_t>(groups.offset[v]);
        const auto last = static_cast<std::size_t>(groups.offset[v + 1]);
        if (last - first < 2) continue;
        group.clear();
        for (std::size_t g = first; g < last; ++g) {
          const auto e = static_cast<std::size_t>(groups.item[g]);
          group.emplace_back(sorted_key(e), e);
        }
        std::sort(group.begin(), group.end());
        std::size_t earliest = 0;  // the first entry of the current run of equal vertex sets
        for (std::size_t g = 1; g < group.size(); ++g) {
          if (group[g].first != group[earliest].first)
            earliest = g;
          else
            found[part].emplace_back(group[g].second, group[earliest].second);
        }
      }
    });
    for (auto& part : found) duplicates.insert(duplicates.end(), part.begin(), part.end());
    parallel_sort(pool, duplicates, [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  findings.reserve(findings.size() + shapes.size() + duplicates.size());
  std::size_t next = 0;
  for (const auto& [e, other] : duplicates) {
    while (next < shapes.size() && shapes[next].index <= e) findings.push_back(shapes[next++]);
    MeshFinding finding;
    finding.kind = tetrahedra ? MeshFindingKind::DuplicateTetrahedron : MeshFindingKind::DuplicateTriangle;
    finding.index = e;
    finding.other = other;
    finding.line = line_of(lines, e);
    finding.value = element_measure(mesh, elements[e]);
    findings.push_back(finding);
  }
  findings.insert(findings.end(), shapes.begin() + static_cast<std::ptrdiff_t>(next), shapes.end());
}

// The vertices no element uses, when the mesh has elements (indices out of range are ignored).
std::vector<std::size_t> unreferenced_vertices(const Mesh& mesh, WorkerPool& pool) {
  const std::size_t n = mesh.points.size();
  if (mesh.tetrahedra.empty() && mesh.triangles.empty()) return {};
  std::vector<std::atomic<std::uint8_t>> referenced(n);  // value-initialised: zero
  const auto mark_all = [&](const auto& elements) {
    pool.run(elements.size(), [&](std::size_t begin, std::size_t end) {
      for (std::size_t e = begin; e < end; ++e) {
        for (const std::int32_t v : elements[e]) {
          if (v >= 0 && static_cast<std::size_t>(v) < n)
            referenced[static_cast<std::size_t>(v)].store(1, std::memory_order_relaxed);
        }
      }
    });
  };
  mark_all(mesh.tetrahedra);
  mark_all(mesh.triangles);
  std::vector<std::vector<std::size_t>> found(pool.parts(n));
  pool.run_parts(n, [&](unsigned part, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      if (!referenced[v].load(std::memory_order_relaxed)) found[part].push_back(v);
  });
  std::vector<std::size_t> unreferenced;
  for (const auto& part : found) unreferenced.insert(unreferenced.end(), part.begin(), part.end());
  return unreferenced;
}

MeshFinding duplicate_vertex_finding(const Mesh& mesh, std::size_t v, std::size_t representative) {
  MeshFinding finding;
  finding.kind = MeshFindingKind::DuplicateVertex;
  finding.index = v;
  finding.other = representative;
  finding.value = distance(mesh.points[v], mesh.points[representative]);
  return finding;
}

std::vector<MeshFinding> duplicate_vertex_findings(const Mesh& mesh, const std::vector<std::size_t>& representative,
                                                   WorkerPool& pool) {
  std::vector<std::vector<MeshFinding>> found(pool.parts(representative.size()));
  pool.run_parts(representative.size(), [&](unsigned part, std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      if (representative[v] != v) found[part].push_back(duplicate_vertex_finding(mesh, v, representative[v]));
  });
  std::vector<MeshFinding> findings;
  for (const auto& part : found) findings.insert(findings.end(), part.begin(), part.end());
  return findings;
}

}  // namespace

std::vector<MeshFinding> check_mesh(const Mesh& mesh, const MeshCheckOptions& options, WorkerPool* given_pool) {
  PoolLease lease = check_pool(mesh, options, given_pool);
  WorkerPool& pool = lease.pool();
  std::vector<MeshFinding> element_findings;
  check_elements(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, options, pool, element_findings);
  std::vector<MeshFinding> triangle_findings;
  check_elements(mesh, mesh.triangles, mesh.triangle_lines, options, pool, triangle_findings);
  std::vector<MeshFinding> findings;
  for (const auto& f : element_findings) {
    if (f.kind == MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : triangle_findings) {
    if (f.kind == MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : element_findings) {
    if (f.kind != MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : triangle_findings) {
    if (f.kind != MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  const std::vector<std::size_t> representative =
      duplicate_representatives(mesh, duplicate_tolerance(mesh, options), pool);
  const std::vector<MeshFinding> duplicate_vertices = duplicate_vertex_findings(mesh, representative, pool);
  findings.insert(findings.end(), duplicate_vertices.begin(), duplicate_vertices.end());
  for (const std::size_t v : unreferenced_vertices(mesh, pool)) {
    MeshFinding finding;
    finding.kind = MeshFindingKind::UnreferencedVertex;
    finding.index = v;
    findings.push_back(finding);
  }
  return findings;
}

std::vector<MeshFinding> degenerate_elements(const Mesh& mesh, const MeshCheckOptions& options,
                                             WorkerPool* given_pool) {
  PoolLease lease = check_pool(mesh, options, given_pool);
  WorkerPool& pool = lease.pool();
  std::vector<MeshFinding> findings;
  const auto keep_degenerate = [&](const std::vector<MeshFinding>& shapes) {
    for (const MeshFinding& f : shapes) {
      if (f.kind == MeshFindingKind::DegenerateTetrahedron || f.kind == MeshFindingKind::DegenerateTriangle)
        findings.push_back(f);
    }
  };
  keep_degenerate(check_shapes(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, options, pool, nullptr));
  keep_degenerate(check_shapes(mesh, mesh.triangles, mesh.triangle_lines, options, pool, nullptr));
  return findings;
}

namespace {

template <std::size_t N>
void repair_elements(Mesh& mesh, std::vector<std::array<std::int32_t, N>>& elements, std::vector<int>& lines,
                     const std::vector<std::size_t>& representative, bool merges, const MeshCheckOptions& options,
                     WorkerPool& pool, std::vector<MeshFinding>& findings) {
  // Check the elements as given (indices of the input mesh), then merge duplicate vertices and check again so that
  // elements made degenerate or duplicate by merging are caught too. Without merges the second check would find
  // nothing: flipping an inverted element negates its volume exactly and changes neither its vertex set nor its
  // edges, so it is skipped.
  std::vector<MeshFinding> original;
  check_elements(mesh, elements, lines, options, pool, original);
  std::vector<std::uint8_t> drop;
  resize_large(drop, elements.size());
  bool dropped = false;
  for (MeshFinding& f : original) {
    switch (f.kind) {
      case MeshFindingKind::InvertedTetrahedron:
        std::swap(elements[f.index][1], elements[f.index][2]);
        break;
      default:
        drop[f.index] = 1;
        dropped = true;
        break;
    }
    f.repaired = true;
    findings.push_back(f);
  }
  if (merges) {
    pool.run(elements.size(), [&](std::size_t begin, std::size_t end) {
      for (std::size_t e = begin; e < end; ++e) {
        if (drop[e]) continue;
        for (auto& v : elements[e]) v = static_cast<std::int32_t>(representative[static_cast<std::size_t>(v)]);
      }
    });
    std::vector<MeshFinding> after_merge;
    check_elements(mesh, elements, lines, options, pool, after_merge);
    for (MeshFinding& f : after_merge) {
      if (drop[f.index]) continue;
      if (f.kind == MeshFindingKind::InvertedTetrahedron) {
        std::swap(elements[f.index][1], elements[f.index][2]);  // merging moved no point, so this cannot happen
      } else {
        drop[f.index] = 1;
        dropped = true;
      }
      f.repaired = true;
      findings.push_back(f);
    }
  }
  if (!dropped) return;
  std::size_t kept = 0;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (drop[e]) continue;
    elements[kept] = elements[e];
    if (e < lines.size()) lines[kept] = lines[e];
    ++kept;
  }
  elements.resize(kept);
  if (lines.size() > kept) lines.resize(kept);
}

template <std::size_t N>
void renumber(std::vector<std::array<std::int32_t, N>>& elements, const std::vector<std::int32_t>& new_index,
              WorkerPool& pool) {
  pool.run(elements.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      for (auto& v : elements[e]) v = new_index[static_cast<std::size_t>(v)];
    }
  });
}

}  // namespace

MeshRepairResult repair_mesh(Mesh& mesh, const MeshCheckOptions& options, WorkerPool* given_pool) {
  PoolLease lease = check_pool(mesh, options, given_pool);
  WorkerPool& pool = lease.pool();
  MeshRepairResult result;
  const std::vector<std::size_t> representative =
      duplicate_representatives(mesh, duplicate_tolerance(mesh, options), pool);
  std::vector<MeshFinding> duplicate_vertices = duplicate_vertex_findings(mesh, representative, pool);
  const bool merges = !duplicate_vertices.empty();
  repair_elements(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, representative, merges, options, pool,
                  result.findings);
  repair_elements(mesh, mesh.triangles, mesh.triangle_lines, representative, merges, options, pool,
                  result.findings);
  const std::size_t n = mesh.points.size();
  std::vector<std::uint8_t> keep;
  resize_large(keep, n);
  std::fill(keep.begin(), keep.end(), std::uint8_t{1});
  for (MeshFinding& f : duplicate_vertices) {
    f.repaired = true;
    keep[f.index] = 0;
  }
  result.findings.insert(result.findings.end(), duplicate_vertices.begin(), duplicate_vertices.end());
  // After the element repair every index is in range and names a representative, so the vertices no element uses
  // are the merged duplicates and the unreferenced ones.
  for (const std::size_t v : unreferenced_vertices(mesh, pool)) {
    if (!keep[v]) continue;
    MeshFinding finding;
    finding.kind = MeshFindingKind::UnreferencedVertex;
    finding.index = v;
    finding.repaired = true;
    result.findings.push_back(finding);
    keep[v] = 0;
  }
  resize_large(result.new_vertex_index, n);
  std::size_t next = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (keep[v]) {
      result.new_vertex_index[v] = static_cast<std::int32_t>(next);
      if (next != v) mesh.points[next] = mesh.points[v];
      ++next;
    } else {
      result.new_vertex_index[v] = -1;
    }
  }
  if (next == n) return result;  // every vertex kept: the indices stand
  for (std::size_t v = 0; v < n; ++v) {
    if (!keep[v] && representative[v] != v) result.new_vertex_index[v] = result.new_vertex_index[representative[v]];
  }
  mesh.points.resize(next);
  renumber(mesh.tetrahedra, result.new_vertex_index, pool);
  renumber(mesh.triangles, result.new_vertex_index, pool);
  return result;
}

std::string finding_message(const MeshFinding& f) {
  std::ostringstream out;
  const bool is_vertex = f.kind == MeshFindingKind::DuplicateVertex || f.kind == MeshFindingKind::UnreferencedVertex;
  const bool is_triangle =
      f.kind == MeshFindingKind::DegenerateTriangle || f.kind == MeshFindingKind::DuplicateTriangle;
  out << (is_vertex ? "vertex " : is_triangle ? "triangle " : "element ") << f.index;
  if (f.line > 0) out << " (line " << f.line << ")";
  switch (f.kind) {
    case MeshFindingKind::IndexOutOfRange:
      out << " refers to a vertex that does not exist";
      break;
    case MeshFindingKind::DegenerateTetrahedron:
      out << " is degenerate (volume " << f.value << ")";
      break;
    case MeshFindingKind::InvertedTetrahedron:
      out << " is inverted (volume " << f.value << ")";
      break;
    case MeshFindingKind::DuplicateTetrahedron:
    case MeshFindingKind::DuplicateTriangle:
      out << " repeats element " << f.other;
      break;
    case MeshFindingKind::DegenerateTriangle:
      out << " is degenerate (area " << f.value << ")";
      break;
    case MeshFindingKind::DuplicateVertex:
      out << " duplicates vertex " << f.other << " (distance " << f.value << ")";
      break;
    case MeshFindingKind::UnreferencedVertex:
      out << " is used by no element";
      break;
  }
  if (f.repaired) {
    switch (f.kind) {
      case MeshFindingKind::InvertedTetrahedron:
        out << "; repaired: two vertices swapped";
        break;
      case MeshFindingKind::DuplicateVertex:
        out << "; repaired: merged";
        break;
      default:
        out << "; repaired: removed";
        break;
    }
  }
  return out.str();
}

}  // namespace fmpc::sim
