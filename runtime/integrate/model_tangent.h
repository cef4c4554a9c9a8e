#pragma once
// The force model's tangent at a state, as sparse matrices over 3 n degrees of freedom (vertex-major, x y z): the
// stiffness K = -df/dx and the damping D = -df/dv of the springs (their blocks of kernels/implicit_math.h: k u u^T
// plus the transverse term, the dashpot c u u^T) and of the tetrahedron field (kernels/tetrahedron_math.h: R K0 R^T or
// the volume term's Gauss-Newton stiffness, and beta_e times it). The nodal and mass damping are per vertex and left
// to the caller. Implicit Euler (cpu_engine.cpp) and the static solver (static_equilibrium.h) both build their
// systems from it, so a new force model adds its blocks here once.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/Sparse>
#pragma GCC diagnostic pop
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

struct ModelTangent {
  Eigen::SparseMatrix<double> stiffness;
  Eigen::SparseMatrix<double> damping;
};

// At `positions` (double), with the springs' current stiffness `spring_stiffness` (one per spring: a strain table's
// last lookup, or springs.stiffness) and, with a strain table, each element's modulus at its current strain.
ModelTangent model_tangent(const SimulationSetup& setup, const std::vector<Point3>& positions,
                           const std::vector<double>& spring_stiffness);

// Each element's linearisation, per term, as implicit Euler's force pass takes it beside the forces at the step's
// start (kernels::element_node_forces_linearised), for the step's tangent to read (ElementTangents::stiffness)
// instead of taking it again at the same positions: the co-rotational law's polar decomposition, once per element
// and step instead of twice (docs/performance.md, "The polar decomposition once a step"). A term's values are read
// only while held: from hold() to release(). The force pass writes element e's from one worker, the assembly reads
// them after it.
class ElementLinearisations {
 public:
  // Term `term`'s room for `count` linearisations of the trivially copyable type Lin, marked held.
  template <typename Lin>
  void hold(std::size_t term, std::size_t count) {
    static_assert(std::is_trivially_copyable_v<Lin>, "a linearisation is copied as bytes");
    if (terms_.size() <= term) terms_.resize(term + 1);
    Term& held = terms_[term];
    held.size = sizeof(Lin);
    held.bytes.resize(sizeof(Lin) * count);
    held.held = true;
  }
  void release() {
    for (Term& term : terms_) term.held = false;
  }
  // Whether term `term` holds linearisations of type Lin.
  template <typename Lin>
  bool holds(std::size_t term) const {
    return term < terms_.size() && terms_[term].held && terms_[term].size == sizeof(Lin);
  }
  template <typename Lin>
  void store(std::size_t term, std::size_t e, const Lin& lin) {
    std::memcpy(terms_[term].bytes.data() + sizeof(Lin) * e, &lin, sizeof(Lin));
  }
  template <typename Lin>
  void load(std::size_t term, std::size_t e, Lin& lin) const {
    std::memcpy(&lin, terms_[term].bytes.data() + sizeof(Lin) * e, sizeof(Lin));
  }

 private:
  struct Term {
    std::vector<unsigned char> bytes;
    std::size_t size = 0;  // sizeof the type held
    bool held = false;
  };
  std::vector<Term> terms_;
};

// The element terms' tangent one element at a time, for an assembler that places the blocks itself (implicit Euler's
// fixed pattern, implicit_system.h): the one place that asks an element kind and its law for the stiffness
// (kernels/element_term.h), so that model_tangent and the assemblers stay apart from the laws' linearisation and
// hold no element kind's node count. Reads the setup for its life; not copyable (its views point at its own strain
// table view).
class ElementTangents {
 public:
  explicit ElementTangents(const SimulationSetup& setup);
  ElementTangents(const ElementTangents&) = delete;
  ElementTangents& operator=(const ElementTangents&) = delete;

  std::size_t term_count() const { return views_.size(); }
  // Nodes per element (the element kind's kNodes), and element e's nodes (vertex indices).
  int nodes() const { return geometry_.nodes_per_element; }
  const std::int32_t* element_nodes(std::size_t e) const {
    return geometry_.nodes.data() + static_cast<std::size_t>(geometry_.nodes_per_element) * e;
  }
  // Term `term`'s (3N x 3N) stiffness of element e with its N = nodes() nodes at `x` (3 N values, node-major),
  // row-major: K[3N (3 a + i) + 3 b + j] couples node a's axis i to node b's axis j, linearised there by the term's
  // element kind and law; returns the element's stiffness damping beta_e (s), 0 when undamped. Where `held` holds the
  // term's linearisations (taken at x), the law's linearisation is read from it rather than taken from x.
  double stiffness(std::size_t term, std::size_t e, const double* x, double* K,
                   const ElementLinearisations* held = nullptr) const;

 private:
  const ElementGeometry& geometry_;
  kernels::StrainTableView table_{nullptr, nullptr, 0};
  std::vector<kernels::ElementTermView<double>> views_;
};

// The most nodes an element kind has (kernels::ElementKinds): the size of an assembler's per-element buffers.
template <typename... Kinds>
constexpr int most_element_nodes(kernels::TypeList<Kinds...>) {
  int most = 0;
  for (const int nodes : {Kinds::kNodes...}) most = nodes > most ? nodes : most;
  return most;
}
inline constexpr int kMostElementNodes = most_element_nodes(kernels::ElementKinds{});

}  // namespace fmpc::sim
