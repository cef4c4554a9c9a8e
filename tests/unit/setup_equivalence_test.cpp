// The O(N log N), multi-threaded host setup against the code it replaced (tests/support/setup_reference.cpp), bit
// for bit: mesh findings and their order, repairs, boundary triangles, springs and their order, CSR, rest lengths,
// stiffness, masses, damping, whole spring models and their error messages, on seeded random meshes with every
// kind of defect, each computed on one thread and on four threads that split even the smallest ranges.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "runtime/integrate/worker_pool.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/mesh/mesh_check.h"
#include "runtime/scene/spring_model_builder.h"
#include "runtime/springs/spring_network.h"
#include "tests/support/setup_reference.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

using Random = std::mt19937_64;

int uniform_int(Random& random, int low, int high) { return std::uniform_int_distribution<int>(low, high)(random); }
double uniform(Random& random, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(random);
}
bool chance(Random& random, double p) { return std::bernoulli_distribution(p)(random); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same_bits(a[i], b[i])) return false;
  return true;
}

bool same_bits(const std::vector<Point3>& a, const std::vector<Point3>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t c = 0; c < 3; ++c)
      if (!same_bits(a[i][c], b[i][c])) return false;
  return true;
}

std::string describe(const std::vector<MeshFinding>& findings) {
  std::string text;
  for (const MeshFinding& f : findings) text += finding_message(f) + " [other " + std::to_string(f.other) + "]\n";
  return text;
}

bool same_findings(const std::vector<MeshFinding>& a, const std::vector<MeshFinding>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].kind != b[i].kind || a[i].index != b[i].index || a[i].other != b[i].other ||
        !same_bits(a[i].value, b[i].value) || a[i].line != b[i].line || a[i].repaired != b[i].repaired)
      return false;
  }
  return true;
}

bool same_mesh(const Mesh& a, const Mesh& b) {
  return same_bits(a.points, b.points) && a.tetrahedra == b.tetrahedra && a.triangles == b.triangles &&
         a.tetrahedron_lines == b.tetrahedron_lines && a.triangle_lines == b.triangle_lines;
}

void check_same_network(const SpringNetwork& a, const SpringNetwork& b, bool measures = true) {
  CHECK(a.vertex_count == b.vertex_count);
  CHECK(a.first == b.first);
  CHECK(a.second == b.second);
  CHECK((a.kind == b.kind));
  if (measures) CHECK(same_bits(a.element_measure, b.element_measure));
  CHECK(same_bits(a.rest_length, b.rest_length));
  CHECK(same_bits(a.stiffness, b.stiffness));
  CHECK(same_bits(a.damping, b.damping));
  CHECK(a.adjacency_offset == b.adjacency_offset);
  CHECK(a.adjacency_spring == b.adjacency_spring);
}

std::vector<std::string> messages(const DiagnosticList& diagnostics) {
  std::vector<std::string> text;
  for (const Diagnostic& d : diagnostics.items())
    text.push_back(d.range.file + ":" + std::to_string(d.range.line) + ": " + d.message);
  return text;
}

// A box of random size and resolution, its points jittered (keeping most tetrahedra positive), then defects: close
// and exact duplicate vertices used by some corners, inverted, duplicated, degenerate and out-of-range elements,
// unreferenced vertices, shuffled elements, source lines, and optionally surface triangles.
Mesh random_mesh(Random& random, bool with_tetrahedra, bool with_triangles, bool defects) {
  BoxSpec spec;
  spec.cells_x = uniform_int(random, 1, 4);
  spec.cells_y = uniform_int(random, 1, 4);
  spec.cells_z = uniform_int(random, 1, 3);
  spec.size = {uniform(random, 0.01, 2.0), uniform(random, 0.01, 2.0), uniform(random, 0.01, 2.0)};
  spec.minimum = {uniform(random, -1.0, 1.0), uniform(random, -1.0, 1.0), uniform(random, -1.0, 1.0)};
  DiagnosticList diagnostics;
  Mesh box = generate_box(spec, diagnostics);
  Mesh mesh;
  mesh.source = "random";
  mesh.points = box.points;
  const double jitter = chance(random, 0.5) ? 0.0 : uniform(random, 0.0, 0.2);
  const double cell = std::min({spec.size[0] / spec.cells_x, spec.size[1] / spec.cells_y, spec.size[2] / spec.cells_z});
  for (Point3& p : mesh.points)
    for (double& c : p) c += jitter * cell * uniform(random, -1.0, 1.0);
  if (with_tetrahedra) mesh.tetrahedra = box.tetrahedra;
  if (with_triangles) {
    mesh.triangles = reference::boundary_triangles(box);
    if (chance(random, 0.3)) {  // a non-manifold edge: a third triangle on some edges
      for (int i = 0; i < 3 && !mesh.triangles.empty(); ++i) {
        Triangle t = mesh.triangles[static_cast<std::size_t>(uniform_int(random, 0, static_cast<int>(mesh.triangles.size()) - 1))];
        t[2] = static_cast<std::int32_t>(uniform_int(random, 0, static_cast<int>(mesh.points.size()) - 1));
        mesh.triangles.push_back(t);
      }
    }
  }
  if (!defects) return mesh;
  const auto n = static_cast<int>(mesh.points.size());
  const auto pick_vertex = [&] { return static_cast<std::int32_t>(uniform_int(random, 0, n - 1)); };
  // Duplicate vertices (exact copies, or within the default tolerance of 1e-9 x the diagonal), some used.
  const int duplicates = chance(random, 0.5) ? uniform_int(random, 1, 6) : 0;
  for (int d = 0; d < duplicates; ++d) {
    const std::int32_t original = pick_vertex();
    Point3 copy = mesh.points[static_cast<std::size_t>(original)];
    if (chance(random, 0.5)) copy[static_cast<std::size_t>(uniform_int(random, 0, 2))] += uniform(random, -1e-11, 1e-11);
    mesh.points.push_back(copy);
    const auto copy_index = static_cast<std::int32_t>(mesh.points.size() - 1);
    auto& elements = mesh.tetrahedra;
    for (auto& t : elements)
      for (auto& v : t)
        if (v == original && chance(random, 0.5)) v = copy_index;
    for (auto& t : mesh.triangles)
      for (auto& v : t)
        if (v == original && chance(random, 0.5)) v = copy_index;
    if (chance(random, 0.3)) mesh.points.push_back(copy);  // a chain of three
  }
  const auto defect_elements = [&](auto& elements) {
    if (elements.empty()) return;
    const auto count = static_cast<int>(elements.size());
    const int edits = uniform_int(random, 0, 5);
    for (int k = 0; k < edits; ++k) {
      auto e = elements[static_cast<std::size_t>(uniform_int(random, 0, count - 1))];
      switch (uniform_int(random, 0, 5)) {
        case 0:  // inverted (tetrahedra) or reoriented
          std::swap(e[0], e[1]);
          elements[static_cast<std::size_t>(uniform_int(random, 0, count - 1))] = e;
          break;
        case 1:  // a duplicate, its vertices permuted
          std::shuffle(e.begin(), e.end(), random);
          elements.push_back(e);
          break;
        case 2:  // a repeated vertex
          e[1] = e[0];
          elements.push_back(e);
          break;
        case 3:  // out of range
          e[static_cast<std::size_t>(uniform_int(random, 0, static_cast<int>(e.size()) - 1))] =
              chance(random, 0.5) ? -1 : static_cast<std::int32_t>(mesh.points.size() + 3);
          elements.push_back(e);
          break;
        case 4: {  // flat: a new vertex in the plane of three others (tetrahedra), or on the line of two
          const Point3& a = mesh.points[static_cast<std::size_t>(e[0])];
          const Point3& b = mesh.points[static_cast<std::size_t>(e[1])];
          const Point3& c = mesh.points[static_cast<std::size_t>(e[2 % e.size()])];
          const double u = uniform(random, 0.1, 0.5), w = e.size() == 4 ? uniform(random, 0.1, 0.4) : 0.0;
          Point3 p;
          for (std::size_t i = 0; i < 3; ++i) p[i] = a[i] + u * (b[i] - a[i]) + w * (c[i] - a[i]);
          mesh.points.push_back(p);
          e[e.size() - 1] = static_cast<std::int32_t>(mesh.points.size() - 1);
          elements.push_back(e);
          break;
        }
        default:  // an exact copy
          elements.push_back(e);
          break;
      }
    }
    std::shuffle(elements.begin(), elements.end(), random);
  };
  defect_elements(mesh.tetrahedra);
  defect_elements(mesh.triangles);
  const int unreferenced = chance(random, 0.5) ? uniform_int(random, 1, 3) : 0;
  for (int u = 0; u < unreferenced; ++u)
    mesh.points.push_back({uniform(random, -2.0, 2.0), uniform(random, -2.0, 2.0), uniform(random, -2.0, 2.0)});
  if (chance(random, 0.7)) {
    for (std::size_t e = 0; e < mesh.tetrahedra.size(); ++e) mesh.tetrahedron_lines.push_back(static_cast<int>(10 + e));
    for (std::size_t e = 0; e < mesh.triangles.size(); ++e) mesh.triangle_lines.push_back(static_cast<int>(500 + e));
    if (chance(random, 0.3) && !mesh.tetrahedron_lines.empty()) mesh.tetrahedron_lines.pop_back();  // shorter: 0
  }
  return mesh;
}

bool indices_in_range(const Mesh& mesh) {
  const auto ok = [&](std::int32_t v) { return v >= 0 && static_cast<std::size_t>(v) < mesh.points.size(); };
  for (const auto& t : mesh.tetrahedra)
    for (const auto v : t)
      if (!ok(v)) return false;
  for (const auto& t : mesh.triangles)
    for (const auto v : t)
      if (!ok(v)) return false;
  return true;
}

StiffnessSpec random_stiffness(Random& random, std::size_t springs) {
  StiffnessSpec spec;
  spec.mapping = static_cast<StiffnessMapping>(uniform_int(random, 0, 3));
  spec.value = uniform(random, 100.0, 10000.0);
  spec.thickness = uniform(random, 0.001, 0.1);
  spec.flexion_fraction = uniform(random, 0.0, 0.5);
  if (chance(random, 0.3)) {
    spec.per_spring.resize(springs);
    for (double& v : spec.per_spring) v = uniform(random, 100.0, 10000.0);
    if (springs > 0 && chance(random, 0.3))  // a bad value somewhere: the first bad spring is named
      spec.per_spring[static_cast<std::size_t>(uniform_int(random, 0, static_cast<int>(springs) - 1))] =
          chance(random, 0.5) ? std::numeric_limits<double>::quiet_NaN() : -1.0;
  }
  return spec;
}

DampingSpec random_damping(Random& random) {
  DampingSpec spec;
  spec.rule = static_cast<DampingSpec::Rule>(uniform_int(random, 0, 2));
  spec.ratio = chance(random, 0.2) ? 0.0 : uniform(random, 0.1, 1.0);
  spec.natural_frequency = uniform(random, 1.0, 100.0);
  spec.value = uniform(random, 0.0, 2.0);
  return spec;
}

MassSpec random_mass(Random& random) {
  MassSpec spec;
  spec.source = chance(random, 0.5) ? MassSpec::Source::Density : MassSpec::Source::TotalMass;
  spec.value = uniform(random, 1.0, 2000.0);
  spec.thickness = uniform(random, 0.001, 0.1);
  return spec;
}

// Runs `check(pool)` with the calling thread alone and with four threads that split every range.
template <class Check>
void on_one_and_four_threads(const Check& check) {
  WorkerPool one(1);
  check(one);
  WorkerPool four(4, 1);
  check(four);
}

void compare_mesh_checks(const Mesh& mesh) {
  const std::vector<MeshFinding> expected = reference::check_mesh(mesh);
  Mesh expected_repaired = mesh;
  const MeshRepairResult expected_repair = reference::repair_mesh(expected_repaired);
  on_one_and_four_threads([&](WorkerPool& pool) {
    const std::vector<MeshFinding> found = check_mesh(mesh, {}, &pool);
    INFO("expected:\n" << describe(expected) << "found:\n" << describe(found));
    CHECK(same_findings(found, expected));
    Mesh repaired = mesh;
    const MeshRepairResult repair = repair_mesh(repaired, {}, &pool);
    INFO("expected repair:\n" << describe(expected_repair.findings) << "found:\n" << describe(repair.findings));
    CHECK(same_findings(repair.findings, expected_repair.findings));
    CHECK(repair.new_vertex_index == expected_repair.new_vertex_index);
    CHECK(same_mesh(repaired, expected_repaired));
    CHECK(boundary_triangles(repaired, &pool) == reference::boundary_triangles(expected_repaired));
  });
}

void compare_networks(const Mesh& mesh, Random& random) {
  DiagnosticList expected_diagnostics;
  TriangleSpringOptions options;
  options.structural = chance(random, 0.8);
  options.flexion = chance(random, 0.7);
  options.bending = chance(random, 0.6);
  options.bending_min_angle_degrees = uniform(random, 90.0, 170.0);
  const bool tetrahedra = !mesh.tetrahedra.empty();
  SpringNetwork expected = tetrahedra ? reference::springs_from_tetrahedra(mesh, expected_diagnostics)
                                      : reference::springs_from_triangles(mesh, options, expected_diagnostics);
  const bool lengths = expected.size() > 0 && reference::compute_rest_lengths(expected, mesh.points, expected_diagnostics);
  const StiffnessSpec stiffness = random_stiffness(random, expected.size());
  const bool stiff = lengths && reference::assign_stiffness(expected, stiffness, expected_diagnostics);
  const MassSpec mass_spec = random_mass(random);
  const std::vector<double> expected_mass = reference::lumped_masses(mesh, mass_spec, expected_diagnostics);
  const DampingSpec damping = random_damping(random);
  if (stiff && !expected_mass.empty()) reference::assign_damping(expected, expected_mass, damping, expected_diagnostics);
  // Half the meshes hand the springs a grouping of their own (as the model builder does), the others let them group.
  const bool grouped = mesh.points.size() % 2 == 0;
  on_one_and_four_threads([&](WorkerPool& pool) {
    DiagnosticList diagnostics;
    const auto springs = [&]() {
      if (!grouped) {
        return tetrahedra ? springs_from_tetrahedra(mesh, diagnostics, &pool)
                          : springs_from_triangles(mesh, options, diagnostics, &pool);
      }
      VertexElements at = elements_at_vertices(mesh, &pool);
      return tetrahedra ? springs_from_tetrahedra(mesh, mesh.points, diagnostics, &pool, std::move(at))
                        : springs_from_triangles(mesh, mesh.points, options, diagnostics, &pool, std::move(at));
    };
    SpringNetwork network = springs();
    const bool with_lengths =
        network.size() > 0 && compute_rest_lengths(network, mesh.points, diagnostics, 1e-9, &pool);
    // The stiffness written over the element measures (ElementMeasures::Release, the model builder's way): the same
    // result, bits and message as beside them, and no measures left.
    SpringNetwork released = network;
    DiagnosticList released_diagnostics = diagnostics;
    const bool released_assigned =
        with_lengths && assign_stiffness(released, stiffness, released_diagnostics, &pool, ElementMeasures::Release);
    const bool assigned = with_lengths && assign_stiffness(network, stiffness, diagnostics, &pool);
    CHECK(released_assigned == assigned);
    if (with_lengths) {
      CHECK(released.element_measure.empty());
      CHECK(same_bits(released.stiffness, network.stiffness));
      CHECK(messages(released_diagnostics) == messages(diagnostics));
    }
    if (assigned) {
      const std::vector<double> mass = lumped_masses(mesh, mass_spec, diagnostics, &pool);
      CHECK(same_bits(mass, expected_mass));
      if (!mass.empty()) assign_damping(network, mass, damping, diagnostics, &pool);
    } else {
      // The reference stopped there too; its masses were computed regardless.
      CHECK(same_bits(lumped_masses(mesh, mass_spec, diagnostics, &pool), expected_mass));
    }
    check_same_network(network, expected);
    CHECK(messages(diagnostics) == messages(expected_diagnostics));
  });
}

void compare_models(const Mesh& mesh, Random& random) {
  SpringModelSpec spec;
  spec.stiffness = random_stiffness(random, 0);
  spec.mass = random_mass(random);
  spec.damping = random_damping(random);
  spec.triangle_springs.bending = chance(random, 0.5);
  spec.length_unit = chance(random, 0.5) ? 1.0 : uniform(random, 0.0005, 2.0);
  DiagnosticList expected_diagnostics;
  const auto expected = reference::build_spring_model(mesh, spec, expected_diagnostics);
  on_one_and_four_threads([&](WorkerPool& pool) {
    DiagnosticList diagnostics;
    const auto setup = build_spring_model(mesh, spec, diagnostics, &pool);
    CHECK(messages(diagnostics) == messages(expected_diagnostics));
    REQUIRE(setup.has_value() == expected.has_value());
    if (!setup) return;
    CHECK(same_bits(setup->rest_positions, expected->rest_positions));
    CHECK(same_bits(setup->mass, expected->mass));
    CHECK(setup->springs.element_measure.empty());  // released once the stiffness is set
    check_same_network(setup->springs, expected->springs, false);
  });
}

}  // namespace

TEST_CASE("setup equivalence: mesh findings, repairs and boundaries match the previous code bit for bit",
          "[sim][setup]") {
  Random random(20240513);
  for (int c = 0; c < 400; ++c) {
    CAPTURE(c);
    const bool tetrahedra = chance(random, 0.7);
    const Mesh mesh = random_mesh(random, tetrahedra, !tetrahedra || chance(random, 0.3), chance(random, 0.85));
    compare_mesh_checks(mesh);
  }
}

TEST_CASE("setup equivalence: springs, CSR, rest lengths, stiffness, masses and damping match bit for bit",
          "[sim][setup]") {
  Random random(77031);
  for (int c = 0; c < 500; ++c) {
    CAPTURE(c);
    const bool tetrahedra = chance(random, 0.6);
    Mesh mesh = random_mesh(random, tetrahedra, !tetrahedra, chance(random, 0.7));
    if (chance(random, 0.7)) reference::repair_mesh(mesh);
    if (!indices_in_range(mesh)) continue;  // the reference reads out of bounds there; index errors: below
    compare_networks(mesh, random);
  }
}

TEST_CASE("setup equivalence: whole spring models and their errors match bit for bit", "[sim][setup]") {
  Random random(5150);
  for (int c = 0; c < 300; ++c) {
    CAPTURE(c);
    const bool tetrahedra = chance(random, 0.6);
    Mesh mesh = random_mesh(random, tetrahedra, !tetrahedra, chance(random, 0.6));
    if (chance(random, 0.7)) reference::repair_mesh(mesh);
    if (!indices_in_range(mesh)) continue;
    compare_models(mesh, random);
  }
}

TEST_CASE("setup equivalence: a 12^3 box and its surface on 1, 3 and 16 threads", "[sim][setup]") {
  BoxSpec spec;
  spec.cells_x = 12;
  spec.cells_y = 11;
  spec.cells_z = 13;
  spec.size = {0.1, 0.12, 0.09};
  DiagnosticList diagnostics;
  Mesh box = generate_box(spec, diagnostics);
  box.points.push_back(box.points[17]);  // one duplicate vertex, used by one tetrahedron
  for (Tetrahedron& t : box.tetrahedra) {
    const auto corner = std::find(t.begin(), t.end(), 17);
    if (corner == t.end()) continue;
    *corner = static_cast<std::int32_t>(box.points.size() - 1);
    break;
  }
  Mesh expected_mesh = box;
  const MeshRepairResult expected_repair = reference::repair_mesh(expected_mesh);
  SpringModelSpec model;
  model.stiffness.mapping = StiffnessMapping::LloydSzekelyHarders2007;
  model.stiffness.value = 4000.0;
  model.length_unit = 0.001;
  DiagnosticList expected_diagnostics;
  const auto expected = reference::build_spring_model(expected_mesh, model, expected_diagnostics);
  REQUIRE(expected);
  for (const unsigned threads : {1u, 3u, 16u}) {
    CAPTURE(threads);
    WorkerPool pool(threads);
    Mesh mesh = box;
    const MeshRepairResult repair = repair_mesh(mesh, {}, &pool);
    CHECK(same_findings(repair.findings, expected_repair.findings));
    CHECK(same_mesh(mesh, expected_mesh));
    DiagnosticList built_diagnostics;
    const auto setup = build_spring_model(mesh, model, built_diagnostics, &pool);
    REQUIRE(setup);
    check_same_network(setup->springs, expected->springs, false);
    CHECK(same_bits(setup->mass, expected->mass));
    CHECK(boundary_triangles(mesh, &pool) == reference::boundary_triangles(expected_mesh));
  }
}

TEST_CASE("setup edge cases: empty meshes, one vertex, coincident points, index errors", "[sim][setup]") {
  on_one_and_four_threads([&](WorkerPool& pool) {
    Mesh empty;
    CHECK(check_mesh(empty, {}, &pool).empty());
    CHECK(repair_mesh(empty, {}, &pool).new_vertex_index.empty());
    CHECK(boundary_triangles(empty, &pool).empty());

    // Every point at one place: tolerance 0 (a zero diagonal), all merged into vertex 0.
    Mesh same;
    same.points.assign(50, Point3{0.5, -1.0, 2.0});
    const std::vector<MeshFinding> findings = check_mesh(same, {}, &pool);
    CHECK(same_findings(findings, reference::check_mesh(same)));
    CHECK(findings.size() == 49);
    for (const MeshFinding& f : findings) CHECK(f.other == 0);

    // A huge tolerance makes every pair close (each part overflows its pair list and is rescanned).
    Mesh cloud;
    Random random(11);
    for (int i = 0; i < 300; ++i) cloud.points.push_back({uniform(random, 0, 1), uniform(random, 0, 1), 0.0});
    MeshCheckOptions wide;
    wide.duplicate_distance = 10.0;
    CHECK(same_findings(check_mesh(cloud, wide, &pool), reference::check_mesh(cloud, wide)));

    // Index errors name the first element and vertex, as before.
    Mesh broken;
    broken.source = "broken";
    broken.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    broken.tetrahedra = {{0, 1, 2, 3}, {0, 1, 9, 7}, {0, -2, 2, 3}};
    broken.tetrahedron_lines = {4, 5, 6};
    DiagnosticList diagnostics, expected;
    CHECK(springs_from_tetrahedra(broken, diagnostics, &pool).size() == 0);
    reference::springs_from_tetrahedra(broken, expected);
    CHECK(messages(diagnostics) == messages(expected));
    CHECK(diagnostics.items().back().message == "tetrahedron 1 refers to vertex 9 of 4; repair the mesh first (repair_mesh)");
    CHECK(lumped_masses(broken, MassSpec{}, diagnostics, &pool).empty());
    CHECK(diagnostics.items().back().range.line == 5);
  });
}

TEST_CASE("non-finite vertices are never duplicates and leave the tolerance finite", "[sim][setup]") {
  Mesh mesh;
  const double inf = std::numeric_limits<double>::infinity();
  mesh.points = {{0, 0, 0}, {inf, 0, 0}, {inf, 0, 0}, {1, 1, 1}, {1, 1, 1}, {std::nan(""), 0, 0}};
  const std::vector<MeshFinding> findings = check_mesh(mesh);
  REQUIRE(findings.size() == 1);
  CHECK(findings[0].kind == MeshFindingKind::DuplicateVertex);
  CHECK(findings[0].index == 4);
  CHECK(findings[0].other == 3);
}

TEST_CASE("parallel_sort and group_by_key give one result for any thread count", "[sim][setup]") {
  Random random(99);
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{100003}}) {
    std::vector<std::uint64_t> values(n);
    for (auto& v : values) v = random() % (n + 1);  // many ties among values; the index breaks them
    std::vector<std::pair<std::uint64_t, std::size_t>> items(n);
    for (std::size_t i = 0; i < n; ++i) items[i] = {values[i], i};
    auto expected = items;
    std::sort(expected.begin(), expected.end());
    for (const unsigned threads : {1u, 2u, 3u, 8u}) {
      WorkerPool pool(threads, threads > 2 ? 1 : 0);
      auto sorted = items;
      parallel_sort(pool, sorted, std::less<std::pair<std::uint64_t, std::size_t>>());
      CHECK(sorted == expected);
      const KeyGroups groups = group_by_key(pool, n + 1, n, [&](std::size_t i, auto emit) {
        emit(static_cast<std::size_t>(values[i]));
        if (values[i] % 3 == 0) emit(static_cast<std::size_t>(n - values[i]));  // a second key for some
      });
      std::vector<std::vector<std::int32_t>> expected_groups(n + 1);
      for (std::size_t i = 0; i < n; ++i) {
        expected_groups[values[i]].push_back(static_cast<std::int32_t>(i));
        if (values[i] % 3 == 0) expected_groups[n - values[i]].push_back(static_cast<std::int32_t>(i));
      }
      for (std::size_t k = 0; k <= n; ++k) {
        std::sort(expected_groups[k].begin(), expected_groups[k].end());
        const std::vector<std::int32_t> got(groups.item.begin() + groups.offset[k],
                                            groups.item.begin() + groups.offset[k + 1]);
        CHECK(got == expected_groups[k]);
      }
    }
  }
}
