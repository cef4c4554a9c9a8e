#pragma once
// The element laws (kernels/laws/) and element kinds (kernels/elements/), each a list in registry order:
// ElementTermView::law and ::element are indices into them. runtime/fem/element_law_registry.cpp has one row per law
// (scene keyword, builder, trade name, docs). A new law is a header in kernels/laws/, one entry in ElementLaws and its
// row; a new element kind a header in kernels/elements/ and one entry in ElementKinds; nothing else names either
// (tests/unit/law_unit_test.cpp).
#include <type_traits>

#include "kernels/elements/linear_nodal_pressure.h"
#include "kernels/elements/linear_tetrahedron.h"
#include "kernels/elements/quadratic_tetrahedron.h"
#include "kernels/fmpc_hd.h"
#include "kernels/laws/corotational_linear.h"
#include "kernels/laws/stable_neo_hookean.h"
#include "kernels/laws/volume_preservation.h"

namespace fmpc::kernels {

template <typename... Types>
struct TypeList {
  static constexpr int count = static_cast<int>(sizeof...(Types));
};

using ElementLaws = TypeList<CorotationalLinear, VolumePreservation, StableNeoHookean>;
using ElementKinds = TypeList<LinearTetrahedron, QuadraticTetrahedron, LinearNodalPressure>;

// The dispatch over a list, defined twice: for host code (launchers, host loops) and for device code (a kernel that
// meets a term at run time), because a host lambda may not be called from a __host__ __device__ function.
#define FMPC_TYPE_LIST_VISIT(ANNOTATION, NAME)                             \
  template <int Index, typename Visit, typename First, typename... Rest>   \
  ANNOTATION auto NAME##_from(int index, Visit& visit) {                   \
    if constexpr (sizeof...(Rest) == 0) {                                  \
      return visit(First{});                                               \
    } else {                                                               \
      if (index == Index) return visit(First{});                           \
      return NAME##_from<Index + 1, Visit, Rest...>(index, visit);         \
    }                                                                      \
  }                                                                        \
  template <typename Visit, typename... Types>                             \
  ANNOTATION auto NAME##_in(TypeList<Types...>, int index, Visit& visit) { \
    return NAME##_from<0, Visit, Types...>(index, visit);                  \
  }

namespace detail {
FMPC_TYPE_LIST_VISIT(inline, host_visit)
#if defined(__CUDACC__)
FMPC_TYPE_LIST_VISIT(__device__ __forceinline__, device_visit)
#endif
template <typename Type, typename First, typename... Rest>
constexpr int type_position() {
  if constexpr (std::is_same_v<Type, First>) {
    return 0;
  } else {
    static_assert(sizeof...(Rest) > 0, "the type is not in the list");
    return 1 + type_position<Type, Rest...>();
  }
}
template <typename Type, typename... Types>
constexpr int type_position_in(TypeList<Types...>) {
  return type_position<Type, Types...>();
}
}  // namespace detail

// Law's index in ElementLaws (what ElementTermView::law holds for it), and an element kind's in ElementKinds.
template <typename Law>
constexpr int element_law_index = detail::type_position_in<Law>(ElementLaws{});
template <typename Element>
constexpr int element_kind_index = detail::type_position_in<Element>(ElementKinds{});

// visit(Law{}) for the law with index `law` (0 <= law < ElementLaws::count; the last law for any other index: the
// setups' validation refuses such indices, sim::validate_setup). Every branch must return the same type.
template <typename Visit>
inline auto visit_element_law(int law, Visit&& visit) {
  return detail::host_visit_in(ElementLaws{}, law, visit);
}

// Every (element kind, law) pair as one list, pair index element * ElementLaws::count + law: the term visits below
// dispatch once over it. Nested visits (a lambda per kind capturing one per law) cost the persistent kernel a third of
// its registers in spills (ptxas, sm_90: 606 bytes in float where one level spills 100).
template <typename Element, typename Law>
struct ElementTermType {
  using element = Element;
  using law = Law;
};
namespace detail {
template <typename Element, typename... Laws>
TypeList<ElementTermType<Element, Laws>...> pairs_of(Element, TypeList<Laws...>);
template <typename... Lists>
struct ConcatenatedTypeLists;
template <typename... Types>
struct ConcatenatedTypeLists<TypeList<Types...>> {
  using type = TypeList<Types...>;
};
template <typename... First, typename... Second, typename... Rest>
struct ConcatenatedTypeLists<TypeList<First...>, TypeList<Second...>, Rest...> {
  using type = typename ConcatenatedTypeLists<TypeList<First..., Second...>, Rest...>::type;
};
template <typename... Elements>
typename ConcatenatedTypeLists<decltype(pairs_of(Elements{}, ElementLaws{}))...>::type all_pairs(TypeList<Elements...>);
}  // namespace detail
using ElementTermTypes = decltype(detail::all_pairs(ElementKinds{}));

// visit(Element{}, Law{}) for a term's element kind and law: the one place the indices become types. Launchers
// dispatch once per launch (static dispatch in their kernels), host loops once per term; visit_element_term_on_device
// serves a kernel that meets a term at run time.
template <typename Visit>
inline auto visit_element_term(int element, int law, Visit&& visit) {
  auto by_pair = [&](auto pair) {
    using Pair = decltype(pair);
    return visit(typename Pair::element{}, typename Pair::law{});
  };
  return detail::host_visit_in(ElementTermTypes{}, element * ElementLaws::count + law, by_pair);
}
#if defined(__CUDACC__)
template <typename Visit>
__device__ __forceinline__ auto visit_element_term_on_device(int element, int law, Visit&& visit) {
  auto by_pair = [&](auto pair) {
    using Pair = decltype(pair);
    return visit(typename Pair::element{}, typename Pair::law{});
  };
  return detail::device_visit_in(ElementTermTypes{}, element * ElementLaws::count + law, by_pair);
}
#endif

// Whether element kind `kind` reads a nodal pass (its kNodalPressure): the engines run element_nodal_shares and
// nodal_pressure_at (kernels/element_term.h) before its element pass.
inline bool element_kind_has_nodal_pass(int kind) {
  return visit_element_term(kind, 0, [](auto element_kind, auto) { return decltype(element_kind)::kNodalPressure; });
}

// Whether the CUDA persistent kernel's element pass holds kind Element: no nodal pass, at most a tetrahedron's four
// nodes. The larger kinds' bodies cost it a 2.8 KB stack frame and spills in every instantiation (docs/performance.md,
// sixteenth run), so they step with the per-step kernels (BatchShape::element_kind_not_persistent).
template <typename Element>
constexpr bool kPersistentElementKind = !Element::kNodalPressure && Element::kNodes <= 4;
inline bool element_kind_runs_persistent(int kind) {
  return visit_element_term(kind, 0,
                            [](auto element_kind, auto) { return kPersistentElementKind<decltype(element_kind)>; });
}

// The kind whose nodes are a tetrahedron's four corners: inversion checks read a mesh without element terms (springs)
// as elements of this kind.
constexpr int kTetrahedronKind = element_kind_index<LinearTetrahedron>;

namespace detail {
template <typename Real, typename First, typename... Rest>
FMPC_HD bool element_inverted_from(int kind, int e, const int* nodes, const Real* x, const Real* y, const Real* z) {
  if constexpr (sizeof...(Rest) > 0) {
    if (kind != element_kind_index<First>) return element_inverted_from<Real, Rest...>(kind, e, nodes, x, y, z);
  }
  constexpr int N = First::kNodes;
  Real p[N][3];
  for (int a = 0; a < N; ++a) {
    const int vertex = nodes[N * e + a];
    p[a][0] = x[vertex];
    p[a][1] = y[vertex];
    p[a][2] = z[vertex];
  }
  return First::inverted(p);
}
template <typename Real, typename... Kinds>
FMPC_HD bool element_inverted_in(TypeList<Kinds...>, int kind, int e, const int* nodes, const Real* x, const Real* y,
                                 const Real* z) {
  return element_inverted_from<Real, Kinds...>(kind, e, nodes, x, y, z);
}
}  // namespace detail

// Whether element e of kind `kind` (index in ElementKinds; `nodes` holds its kNodes per element) is inverted or flat
// at positions (x, y, z): the kind's own test (the linear tetrahedron's signed volume, the quadratic one's Jacobian
// at its quadrature points), for the inversion counts of the CPU loop and the CUDA kernels alike. A dispatch of its
// own over the kinds, not visit_element_term: it serves host and device code, and needs no law.
template <typename Real>
FMPC_HD bool element_inverted(int kind, int e, const int* nodes, const Real* x, const Real* y, const Real* z) {
  return detail::element_inverted_in(ElementKinds{}, kind, e, nodes, x, y, z);
}

}  // namespace fmpc::kernels
