#pragma once
// The element laws (kernels/laws/), in registry order: ElementTermView::law is an index into this list, and
// runtime/fem/element_law_registry.cpp has one row per entry (scene keyword, builder, trade name, docs). A new law is
// a header in kernels/laws/, one entry here and its row there; nothing else names it (tests/unit/law_unit_test.cpp).
#include <type_traits>

#include "kernels/fmpc_hd.h"
#include "kernels/laws/corotational_linear.h"
#include "kernels/laws/volume_preservation.h"

namespace fmpc::kernels {

template <typename... Laws>
struct ElementLawList {
  static constexpr int count = static_cast<int>(sizeof...(Laws));
};

using ElementLaws = ElementLawList<CorotationalLinear, VolumePreservation>;

// The dispatch over the list, defined twice: for host code (launchers, host loops) and for device code (a kernel
// that meets a term's law at run time), because a host lambda may not be called from a __host__ __device__ function.
#define FMPC_ELEMENT_LAW_VISIT(ANNOTATION, NAME)                              \
  template <int Index, typename Visit, typename Law, typename... Rest>        \
  ANNOTATION auto NAME##_from(int law, Visit& visit) {                        \
    if constexpr (sizeof...(Rest) == 0) {                                     \
      return visit(Law{});                                                    \
    } else {                                                                  \
      if (law == Index) return visit(Law{});                                  \
      return NAME##_from<Index + 1, Visit, Rest...>(law, visit);              \
    }                                                                         \
  }                                                                           \
  template <typename Visit, typename... Laws>                                 \
  ANNOTATION auto NAME##_in(ElementLawList<Laws...>, int law, Visit& visit) { \
    return NAME##_from<0, Visit, Laws...>(law, visit);                        \
  }

namespace detail {
FMPC_ELEMENT_LAW_VISIT(inline, host_visit)
#if defined(__CUDACC__)
FMPC_ELEMENT_LAW_VISIT(__device__ __forceinline__, device_visit)
#endif
template <typename Law, typename First, typename... Rest>
constexpr int law_position() {
  if constexpr (std::is_same_v<Law, First>) {
    return 0;
  } else {
    static_assert(sizeof...(Rest) > 0, "the law is not in ElementLaws");
    return 1 + law_position<Law, Rest...>();
  }
}
template <typename Law, typename... Laws>
constexpr int law_position_in(ElementLawList<Laws...>) {
  return law_position<Law, Laws...>();
}
}  // namespace detail

// Law's index in ElementLaws (what ElementTermView::law holds for it).
template <typename Law>
constexpr int element_law_index = detail::law_position_in<Law>(ElementLaws{});

// visit(Law{}) for the law with index `law` (0 <= law < ElementLaws::count; the last law for any other index: the
// setups' validation refuses such indices, sim::validate_setup). Every branch must return the same type. The one
// place a law index becomes a type: launchers dispatch on it once (static dispatch in their kernels), host loops once
// per term; visit_element_law_on_device serves a kernel that meets a term at run time.
template <typename Visit>
inline auto visit_element_law(int law, Visit&& visit) {
  return detail::host_visit_in(ElementLaws{}, law, visit);
}
#if defined(__CUDACC__)
template <typename Visit>
__device__ __forceinline__ auto visit_element_law_on_device(int law, Visit&& visit) {
  return detail::device_visit_in(ElementLaws{}, law, visit);
}
#endif

}  // namespace fmpc::kernels
