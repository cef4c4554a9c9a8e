// The element laws as units (issue 25, item 1; docs/simulator.md, "Adding a law"): every law of kernels::ElementLaws
// has its registry row, passes the same physical checks (forces are the energy's negative gradient, the stiffness
// blocks are the forces' derivative, the whole matrix and the action agree with the blocks, the stable step's bound
// holds the largest eigenvalue), and no source file outside its kernels header and the registry names it.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The text with comments removed (// to the end of the line, /* ... */), string literals kept.
std::string without_comments(const std::string& text) {
  std::string out;
  bool in_string = false, in_char = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string || in_char) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) {
        out += text[++i];
      } else if ((in_string && c == '"') || (in_char && c == '\'')) {
        in_string = in_char = false;
      }
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      while (i < text.size() && text[i] != '\n') ++i;
      out += '\n';
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      i += 2;
      while (i + 1 < text.size() && !(text[i] == '*' && text[i + 1] == '/')) ++i;
      ++i;
      continue;
    }
    in_string = c == '"';
    in_char = c == '\'';
    out += c;
  }
  return out;
}

// Whether `text` holds `name`: as a whole identifier when `identifier` (no letter, digit or underscore on either
// side), else as it is. A plain search: std::regex over every source file took most of this test's time.
bool holds_name(const std::string& text, const std::string& name, bool identifier) {
  const auto word_char = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; };
  for (std::size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
    if (!identifier) return true;
    const std::size_t end = at + name.size();
    if ((at == 0 || !word_char(text[at - 1])) && (end == text.size() || !word_char(text[end]))) return true;
  }
  return false;
}

// A regular tetrahedron of 1 cm, slightly distorted, positively oriented; Dm^-1 and V0.
struct Element {
  double rest[4][3];
  double rest_inverse[9];
  double volume;
};

Element test_element() {
  Element e{{{0, 0, 0}, {0.011, 0.001, 0}, {0.005, 0.009, 0.001}, {0.004, 0.003, 0.0095}}, {}, 0.0};
  double dm[9];
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 3; ++a) dm[3 * i + a] = e.rest[a + 1][i] - e.rest[0][i];
  const Eigen::Matrix3d inverse = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(dm).inverse();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e.rest_inverse[3 * i + j] = inverse(i, j);
  e.volume = kernels::tetrahedron_volume(e.rest);
  return e;
}

// One element of kind `kind` under `row`'s law at E = 5 kPa, nu = 0.3 (the law's builder), over the test element;
// the view points into the struct and `e`.
struct LawTerm {
  ElementLawBuild build;
  std::int32_t nodes[32], slots[32];
  kernels::ElementTermView<double> view{};
};

void make_law_term(const ElementLawRow& row, int kind, const Element& e, LawTerm& out) {
  ElementMaterial material;
  material.youngs_modulus = {5000.0};
  material.poisson_ratio = {0.3};
  DiagnosticList diagnostics;
  auto build = row.build(material, diagnostics);
  REQUIRE(build);
  REQUIRE(build->term.law == row.law);
  out.build = std::move(*build);
  for (int a = 0; a < 32; ++a) out.nodes[a] = out.slots[a] = a;
  out.view = {};
  out.view.law = row.law;
  out.view.element = kind;
  out.view.count = 1;
  out.view.corners = out.nodes;
  out.view.corner_slot = out.slots;
  out.view.rest_inverse = e.rest_inverse;
  out.view.rest_volume = &e.volume;
  for (int p = 0; p < kernels::kMostLawParameters; ++p)
    out.view.parameter[p] = out.build.term.parameter[p].empty() ? nullptr : out.build.term.parameter[p].data();
}

// check(row, kind, view) for every element kind with every law, on make_law_term's element.
template <typename Check>
void for_every_kind_and_law(const Element& e, Check check) {
  for (int kind = 0; kind < kernels::ElementKinds::count; ++kind)
    for (const ElementLawRow& row : element_law_rows()) {
      INFO("element kind " << kind << ", law " << row.keyword);
      LawTerm term;
      make_law_term(row, kind, e, term);
      check(row, kind, term.view);
    }
}

}  // namespace

TEST_CASE("every element law has its registry row, in kernels::ElementLaws' order", "[fem][law]") {
  const std::vector<ElementLawRow>& rows = element_law_rows();
  REQUIRE(static_cast<int>(rows.size()) == kernels::ElementLaws::count);
  std::set<std::string> names;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ElementLawRow& row = rows[i];
    INFO("row " << i << ": " << row.keyword);
    CHECK(row.law == static_cast<int>(i));
    CHECK(&element_law_row(row.law) == &row);
    CHECK(row.build != nullptr);
    CHECK(std::string(row.description).size() > 20);
    const char* stress =
        kernels::visit_element_law(row.law, [](auto element_law) { return decltype(element_law)::kStressOutput; });
    CHECK(std::string(row.stress_output) == stress);
    // No two laws share a name: scenes and --models tell the laws apart by them (a law may use one name twice).
    std::set<std::string> own = {row.keyword, row.trade_name};
    if (row.model_keyword != nullptr) {
      own.insert(row.model_keyword);
      CHECK(element_law_by_model_keyword(row.model_keyword) == &row);
    }
    for (const std::string& name : own) CHECK(names.insert(name).second);
    CHECK(element_law_by_trade_name(row.trade_name) == &row);
  }
  CHECK(element_law_beside_springs().beside_springs);
  CHECK(default_fem_law().model_keyword != nullptr);
}

TEST_CASE("every element kind has its registry row, in kernels::ElementKinds' order", "[fem][law]") {
  const std::vector<ElementKindRow>& rows = element_kind_rows();
  REQUIRE(static_cast<int>(rows.size()) == kernels::ElementKinds::count);
  std::set<std::string> names;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const ElementKindRow& row = rows[i];
    INFO("row " << i << ": " << row.keyword);
    CHECK(row.kind == static_cast<int>(i));
    CHECK(&element_kind_row(row.kind) == &row);
    CHECK(element_kind_by_keyword(row.keyword) == &row);
    CHECK(names.insert(row.keyword).second);
    CHECK(std::string(row.description).size() > 20);
  }
  std::vector<std::string> in_order;
  for (const ElementKindRow& row : rows) in_order.emplace_back(row.keyword);
  CHECK(element_kind_keywords() == in_order);
  CHECK(element_kind_by_keyword("no such kind") == nullptr);
  CHECK(&default_element_kind() == &rows.front());
  // The laws fem: {law: ...} takes: every row that is a model of its own, by its keyword.
  for (const ElementLawRow& row : element_law_rows())
    CHECK(fem_law_by_keyword(row.keyword) == (row.beside_springs ? nullptr : &row));
  CHECK(fem_law_by_keyword(default_fem_law().keyword) == &default_fem_law());
}

TEST_CASE(
    "every element kind with every law: forces are -dW/dx, the tangent is -df/dx at rest, its action, diagonal "
    "and bound agree",
    "[fem][law]") {
  const Element e = test_element();
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  for_every_kind_and_law(e, [&](const ElementLawRow& row, int kind, kernels::ElementTermView<double>& view) {
    kernels::visit_element_term(kind, row.law, [&](auto element_kind, auto element_law) {
      using Kind = decltype(element_kind);
      using Law = decltype(element_law);
      constexpr int N = Kind::kNodes, D = 3 * N;
      REQUIRE(N <= 32);
      // The kind's test element: the tetrahedron's corners and the kind's further rest nodes.
      double rest[N][3];
      kernels::element_rest_nodes<Kind>(e.rest, rest);
      // A kind with a nodal pass reads its nodes' pressure: for the lone element each node's patch is the element
      // itself (theta_a = J - 1, p_a = lambda (J - 1)), refreshed at every position the checks evaluate.
      double nodal_pressure[32] = {}, nodal_dilatation[32] = {};
      view.nodal_pressure = nodal_pressure;
      view.nodal_dilatation = nodal_dilatation;
      const auto at = [&](const double(&positions)[N][3]) -> const double(&)[N][3] {
        if constexpr (Kind::kNodalPressure) {
          double share[3];
          Kind::template nodal_shares<Law>(view, 0, positions, share);
          for (int a = 0; a < N; ++a) {
            nodal_dilatation[a] = share[0] / share[1];
            nodal_pressure[a] = share[2] / share[1] * nodal_dilatation[a];
          }
        }
        return positions;
      };
      // An affine motion x = A X + b gives F = A at every point of every kind: the energy is V0 W(A).
      {
        const double A[9] = {1.05, 0.02, -0.03, 0.01, 0.97, 0.04, -0.02, 0.03, 1.02};
        double x[N][3];
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i)
            x[a][i] = A[3 * i] * rest[a][0] + A[3 * i + 1] * rest[a][1] + A[3 * i + 2] * rest[a][2] + 0.01 * i;
        // A kind with a nodal pass: the law's shear part plus lambda/2 (J - 1)^2.
        double volumetric = 0.0;
        if constexpr (Kind::kNodalPressure) {
          const double change = kernels::determinant_minus_one(A);
          volumetric = Law::volumetric_modulus(Law::material(view, 0)) * change * change / 2;
        }
        const double expected =
            e.volume * (Law::energy_density(Kind::template point_material<Law>(view, 0), A) + volumetric);
        CHECK(Kind::template energy<Law>(view, 0, at(x)) == Approx(expected).epsilon(1e-9));
      }
      const double(*undamped)[3] = nullptr;
      for (int n = 0; n < 50; ++n) {
        // A random deformation of up to 8 % per coordinate, rigidly shifted.
        double x[N][3], f[N][3];
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i) x[a][i] = rest[a][i] * (1.0 + jitter(rng)) + 0.02;
        Kind::template forces<Law>(view, 0, at(x), undamped, f);
        const double scale = 5000.0 * 1e-4;  // N: E l^2 for l = 1 cm
        const double h = 1e-9;
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i) {
            double plus[N][3], minus[N][3];
            std::copy(&x[0][0], &x[0][0] + D, &plus[0][0]);
            std::copy(&x[0][0], &x[0][0] + D, &minus[0][0]);
            plus[a][i] += h;
            minus[a][i] -= h;
            const double gradient =
                (Kind::template energy<Law>(view, 0, at(plus)) - Kind::template energy<Law>(view, 0, at(minus))) /
                (2 * h);
            CHECK(std::abs(f[a][i] + gradient) < 1e-5 * scale);
          }
        double sum[3] = {0, 0, 0};
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i) sum[i] += f[a][i];
        for (int i = 0; i < 3; ++i) CHECK(std::abs(sum[i]) < 1e-12 * scale);
      }
      // At rest the tangent is the forces' derivative; the action, the diagonal and the bound agree with it.
      double x[N][3];
      std::copy(&rest[0][0], &rest[0][0] + D, &x[0][0]);
      typename Kind::template Linearisation<Law> lin{};
      Kind::template linearise<Law>(view, 0, x, lin);
      double whole[D * D];
      Kind::template stiffness_matrix<Law>(view, 0, lin, whole);
      Eigen::Matrix<double, D, D> K;
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) K(r, c) = whole[D * r + c];
      const Eigen::Matrix<double, D, D> local = K;  // what the kind's action and diagonal give
      // A kind with a nodal pass: its element-local tangent plus the nodal Gauss-Newton term, for the lone element
      // lambda / V0 dV dV^T (model_tangent's B^T D B with B = dV/4 per node, D = lambda / (V0/4)).
      if constexpr (Kind::kNodalPressure) {
        double dV[N][3];
        Kind::volume_gradient(view, 0, x, dV);
        const double lambda = Law::volumetric_modulus(Law::material(view, 0));
        for (int r = 0; r < D; ++r)
          for (int c = 0; c < D; ++c) K(r, c) += lambda / e.volume * dV[r / 3][r % 3] * dV[c / 3][c % 3];
      }
      const double largest_entry = K.cwiseAbs().maxCoeff();
      REQUIRE(largest_entry > 0.0);
      CHECK((K - K.transpose()).cwiseAbs().maxCoeff() < 1e-12 * largest_entry);
      const double h = 1e-8;
      for (int b = 0; b < N; ++b)
        for (int j = 0; j < 3; ++j) {
          double plus[N][3], minus[N][3], fp[N][3], fm[N][3];
          std::copy(&x[0][0], &x[0][0] + D, &plus[0][0]);
          std::copy(&x[0][0], &x[0][0] + D, &minus[0][0]);
          plus[b][j] += h;
          minus[b][j] -= h;
          Kind::template forces<Law>(view, 0, at(plus), undamped, fp);
          Kind::template forces<Law>(view, 0, at(minus), undamped, fm);
          for (int a = 0; a < N; ++a)
            for (int i = 0; i < 3; ++i)
              CHECK(std::abs(-(fp[a][i] - fm[a][i]) / (2 * h) - K(3 * a + i, 3 * b + j)) < 1e-5 * largest_entry);
        }
      double p[N][3], out[N][3], diagonal[N][3];
      Eigen::Matrix<double, D, 1> pv;
      for (int a = 0; a < N; ++a)
        for (int i = 0; i < 3; ++i) p[a][i] = pv[3 * a + i] = std::sin(1.0 + 3 * a + i);
      Kind::template stiffness_action<Law>(view, 0, lin, p, out);
      Kind::template stiffness_diagonal<Law>(view, 0, lin, diagonal);
      const Eigen::Matrix<double, D, 1> product = local * pv;
      for (int r = 0; r < D; ++r) {
        CHECK(out[r / 3][r % 3] == Approx(product[r]).margin(1e-12 * largest_entry));
        CHECK(diagonal[r / 3][r % 3] == Approx(local(r, r)).margin(1e-12 * largest_entry));
      }
      // Deformed, the whole matrix (a kind's closed form where it has one: kernels/elements/corner_tetrahedron.h)
      // is the action's columns to round-off.
      for (int n = 0; n < 10; ++n) {
        double moved[N][3], matrix[D * D];
        for (int a = 0; a < N; ++a)
          for (int i = 0; i < 3; ++i) moved[a][i] = rest[a][i] * (1.0 + jitter(rng)) + 0.02;
        typename Kind::template Linearisation<Law> there{};
        Kind::template linearise<Law>(view, 0, at(moved), there);
        Kind::template stiffness_matrix<Law>(view, 0, there, matrix);
        for (int b = 0; b < N; ++b)
          for (int j = 0; j < 3; ++j) {
            double column[N][3];
            Kind::template stiffness_column<Law>(view, 0, there, b, j, column);
            for (int a = 0; a < N; ++a)
              for (int i = 0; i < 3; ++i)
                CHECK(matrix[D * (3 * a + i) + 3 * b + j] == Approx(column[a][i]).margin(1e-12 * largest_entry));
          }
      }
      const double eigenvalue =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, D, D>>(K).eigenvalues().maxCoeff();
      const double bound = Kind::template stiffness_bound<Law>(view, 0);
      INFO("bound / largest eigenvalue " << bound / eigenvalue);
      CHECK(bound >= eigenvalue * (1 - 1e-12));
      CHECK(bound <= 4 * eigenvalue);  // a bound, not a guess: within the norms' known slack
      // At rest: no force, no energy, no stress output.
      double f[N][3];
      Kind::template forces<Law>(view, 0, at(x), undamped, f);
      for (int a = 0; a < N; ++a)
        for (int i = 0; i < 3; ++i) CHECK(std::abs(f[a][i]) < 1e-12 * 5000.0 * 1e-4);
      CHECK(std::abs(Kind::template energy<Law>(view, 0, x)) < 1e-18);
      CHECK(std::abs(Kind::template stress_output<Law>(view, 0, x)) < 1e-9 * 5000.0);
    });
  });
}

TEST_CASE("a kind's forces with its linearisation have forces' and linearise's bits, damped or not, inverted too",
          "[fem][law]") {
  // Implicit Euler's force pass keeps the linearisation it takes beside the forces for the step's tangent
  // (kernels::element_node_forces_linearised): the step's bits are the same only if both are.
  const Element e = test_element();
  std::mt19937_64 rng(27);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  const double beta = 0.01;
  int kinds_checked = 0;
  for_every_kind_and_law(e, [&](const ElementLawRow& row, int kind, kernels::ElementTermView<double>& view) {
    double nodal_pressure[32], nodal_dilatation[32];
    for (int a = 0; a < 32; ++a) {
      nodal_pressure[a] = 100.0 * std::sin(1.0 + a);
      nodal_dilatation[a] = 0.01 * std::cos(1.0 + a);
    }
    view.nodal_pressure = nodal_pressure;
    view.nodal_dilatation = nodal_dilatation;
    kernels::visit_element_term(kind, row.law, [&](auto element_kind, auto element_law) {
      using Kind = decltype(element_kind);
      using Law = decltype(element_law);
      if constexpr (kernels::HasForcesAndLinearisation<Kind, Law>::value) {
        using Lin = typename Kind::template Linearisation<Law>;
        constexpr int N = Kind::kNodes;
        ++kinds_checked;
        double rest[N][3];
        kernels::element_rest_nodes<Kind>(e.rest, rest);
        for (int n = 0; n < 20; ++n) {
          // At rest, inverted (node 0 reflected through the opposite face's centre), then random deformations of
          // up to 8 %.
          double x[N][3], v[N][3];
          for (int a = 0; a < N; ++a)
            for (int i = 0; i < 3; ++i) {
              x[a][i] = n == 0 ? rest[a][i] : rest[a][i] * (1.0 + jitter(rng)) + 0.02;
              v[a][i] = 0.1 * jitter(rng);
            }
          if (n == 1) {
            for (int i = 0; i < 3; ++i) x[0][i] = 2.0 * (x[1][i] + x[2][i] + x[3][i]) / 3.0 - x[0][i];
            REQUIRE(Kind::inverted(x));
          }
          for (const bool damped : {false, true}) {
            INFO("deformation " << n << (damped ? ", damped" : ""));
            view.stiffness_damping = damped ? &beta : nullptr;
            const double(*velocity)[3] = damped ? v : nullptr;
            double f[N][3], g[N][3];
            Lin linearised{}, kept;
            std::memset(&kept, 0xff, sizeof kept);
            Kind::template forces<Law>(view, 0, x, velocity, f);
            Kind::template linearise<Law>(view, 0, x, linearised);
            Kind::template forces_and_linearisation<Law>(view, 0, x, velocity, kept, g);
            CHECK(std::memcmp(f, g, sizeof f) == 0);
            CHECK(std::memcmp(&linearised, &kept, sizeof kept) == 0);
          }
        }
      }
    });
  });
  // Every law on the corner tetrahedra's kinds (the linear tetrahedron and the nodal pressure one).
  CHECK(kinds_checked >= 2 * static_cast<int>(element_law_rows().size()));
}

TEST_CASE("a law or an element kind is named only in its kernels header, the lists and the registry", "[fem][law]") {
  const std::filesystem::path root = FMPC_SOURCE_DIR;
  // The laws' type names, from ElementLaws' definition; their headers are kernels/laws/*.h.
  const std::string laws_header = read_file(root / "kernels/element_laws.h");
  std::smatch list;
  REQUIRE(std::regex_search(laws_header, list, std::regex(R"(using ElementLaws = TypeList<([^>]*)>;)")));
  std::vector<std::string> types;
  {
    std::istringstream names(list[1].str());
    for (std::string name; std::getline(names, name, ',');) {
      name.erase(0, name.find_first_not_of(' '));
      name.erase(name.find_last_not_of(' ') + 1);
      types.push_back(name);
    }
  }
  REQUIRE(static_cast<int>(types.size()) == kernels::ElementLaws::count);
  // What names a law: its type name (an identifier) and its registry names (whole string literals).
  struct Name {
    std::string text;
    bool identifier;
    std::filesystem::path home;  // the law's header, where its name may appear
  };
  std::vector<Name> names;
  std::map<std::string, std::filesystem::path> header_of;
  for (const auto& entry : std::filesystem::directory_iterator(root / "kernels/laws")) {
    const std::string text = without_comments(read_file(entry.path()));
    for (const std::string& type : types)
      if (std::regex_search(text, std::regex("struct " + type + R"(\b[^{;]*\{)"))) header_of[type] = entry.path();
  }
  for (std::size_t law = 0; law < types.size(); ++law) {
    INFO("law " << types[law]);
    REQUIRE(header_of.count(types[law]) == 1);
    const std::filesystem::path home = header_of[types[law]];
    names.push_back({types[law], true, home});
    const ElementLawRow& row = element_law_row(static_cast<int>(law));
    for (const char* literal : {row.keyword, row.model_keyword, row.trade_name})
      if (literal != nullptr) names.push_back({"\"" + std::string(literal) + "\"", false, home});
  }
  // The element kinds' type names: only in their header, the lists and their geometry builders (runtime/fem/).
  std::smatch kinds;
  REQUIRE(std::regex_search(laws_header, kinds, std::regex(R"(using ElementKinds = TypeList<([^>]*)>;)")));
  std::istringstream kind_names(kinds[1].str());
  for (std::string name; std::getline(kind_names, name, ',');) {
    name.erase(0, name.find_first_not_of(' '));
    name.erase(name.find_last_not_of(' ') + 1);
    std::filesystem::path home;
    for (const auto& entry : std::filesystem::directory_iterator(root / "kernels/elements"))
      if (std::regex_search(without_comments(read_file(entry.path())), std::regex("struct " + name + R"(\b[^{;]*\{)")))
        home = entry.path();
    INFO("element kind " << name);
    REQUIRE(!home.empty());
    names.push_back({name, true, home});
  }
  const std::set<std::filesystem::path> registry = {
      root / "kernels/element_laws.h", root / "runtime/fem/element_terms.cpp",
      root / "runtime/fem/element_law_registry.h", root / "runtime/fem/element_law_registry.cpp"};
  std::vector<std::string> offenders;
  std::size_t files = 0;
  for (const char* folder : {"runtime", "kernels", "tools", "python", "bench", "compiler"}) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / folder)) {
      const std::string extension = entry.path().extension().string();
      if (!entry.is_regular_file() ||
          (extension != ".h" && extension != ".cpp" && extension != ".cu" && extension != ".cuh" && extension != ".py"))
        continue;
      if (registry.count(entry.path())) continue;
      ++files;
      const std::string text = without_comments(read_file(entry.path()));
      for (const Name& name : names)
        if (entry.path() != name.home && holds_name(text, name.text, name.identifier))
          offenders.push_back(std::filesystem::relative(entry.path(), root).string() + " names " + name.text);
    }
  }
  CHECK(files > 100);
  for (const std::string& offender : offenders) FAIL_CHECK(offender);
}
