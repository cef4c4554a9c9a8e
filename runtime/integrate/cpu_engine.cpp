#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "kernels/element_laws.h"
#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"
#include "kernels/internal_force_math.h"
#include "kernels/spring_math.h"
#include "kernels/strain_table_math.h"
#include "runtime/integrate/implicit_contact.h"
#include "runtime/integrate/implicit_solver.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

namespace {

template <typename Real>
struct Vector3Arrays {
  std::vector<Real> x, y, z;
  void resize(std::size_t n) {
    x.assign(n, Real(0));
    y.assign(n, Real(0));
    z.assign(n, Real(0));
  }
};

// One scene's state and steps on the CPU, what CpuEngine runs side by side (a virtual call per scene and step
// chunk, never per element).
class CpuSceneBase {
 public:
  virtual ~CpuSceneBase() = default;
  virtual std::size_t steps_taken() const = 0;
  // Steps to `end` or, earlier, to the first step that leaves a non-finite position or velocity.
  virtual void run_to(std::size_t end, DiagnosticList& diagnostics) = 0;
  // The smallest vertex with a non-finite position or velocity now, or the vertex count.
  virtual std::size_t first_non_finite_vertex() const = 0;
  virtual InversionCount count_inversions() const = 0;
  virtual void save_checkpoint() = 0;
  virtual void restore_checkpoint() = 0;
  virtual const ImplicitSolverLog& implicit_log() const = 0;
  virtual std::vector<ImplicitStepRecord> take_implicit_steps() = 0;
  virtual std::vector<Point3> positions() const = 0;
  virtual std::vector<Point3> velocities() const = 0;
  virtual double kinetic_energy() const = 0;
  virtual double potential_energy() const = 0;
  virtual ProbeReading probe_reading() const = 0;
  virtual std::vector<double> current_stiffness() const = 0;
  virtual const SimulationSetup& setup() const = 0;
  virtual void set_contact(const std::vector<double>& stiffness, const std::vector<double>& damping) = 0;
  virtual void set_tool_shapes(const std::vector<kernels::ToolShape<double>>& shapes) = 0;
  virtual void refresh_material() = 0;
};

template <typename Real>
class CpuScene final : public CpuSceneBase {
 public:
  CpuScene(const SimulationSetup& setup, const StabilityReport& stability)
      : setup_(setup), stability_(stability), pool_(std::max(1u, setup.threads)), n_(setup.rest_positions.size()) {
    const SpringNetwork& net = setup_.springs;
    const auto convert = [](const std::vector<double>& in) {
      std::vector<Real> out(in.size());
      for (std::size_t i = 0; i < in.size(); ++i) out[i] = static_cast<Real>(in[i]);
      return out;
    };
    rest_length_ = convert(net.rest_length);
    stiffness_ = convert(net.stiffness);
    damping_ = convert(net.damping);  // empty without damping
    mass_ = convert(setup.mass);
    // Displacement probes' vertices are held (moved kinematically) only after the initial velocities are taken.
    fixed_ = held_axes(setup);
    std::vector<unsigned char> held_at_start(n_, 0);
    for (std::size_t v = 0; v < n_ && setup.fixed_axes.size() == n_; ++v) held_at_start[v] = setup.fixed_axes[v];
    for (const auto v : setup.fixed_vertices) held_at_start[static_cast<std::size_t>(v)] = kernels::kAllAxesFixed;
    position_.resize(n_);
    velocity_.resize(n_);
    rest_.resize(n_);
    acceleration_.resize(n_);
    for (std::size_t v = 0; v < n_; ++v) {
      const Point3& r = setup.rest_positions[v];
      const Point3& p = setup.initial_positions.empty() ? r : setup.initial_positions[v];
      rest_.x[v] = static_cast<Real>(r[0]);
      rest_.y[v] = static_cast<Real>(r[1]);
      rest_.z[v] = static_cast<Real>(r[2]);
      position_.x[v] = static_cast<Real>(p[0]);
      position_.y[v] = static_cast<Real>(p[1]);
      position_.z[v] = static_cast<Real>(p[2]);
      if (!setup.initial_velocities.empty()) {
        const unsigned char held = held_at_start[v];
        velocity_.x[v] = kernels::axis_fixed(held, 0) ? Real(0) : static_cast<Real>(setup.initial_velocities[v][0]);
        velocity_.y[v] = kernels::axis_fixed(held, 1) ? Real(0) : static_cast<Real>(setup.initial_velocities[v][1]);
        velocity_.z[v] = kernels::axis_fixed(held, 2) ? Real(0) : static_cast<Real>(setup.initial_velocities[v][2]);
      }
    }
    const bool probe_force = setup.probe && setup.probe->mode == ProbeLoad::Mode::Force;
    if (probe_force && setup.external_forces.empty()) force_.resize(n_);
    if (!setup.external_forces.empty()) {
      force_.resize(n_);
      for (std::size_t v = 0; v < n_; ++v) {
        force_.x[v] = static_cast<Real>(setup.external_forces[v][0]);
        force_.y[v] = static_cast<Real>(setup.external_forces[v][1]);
        force_.z[v] = static_cast<Real>(setup.external_forces[v][2]);
      }
    }
    network_view_.adjacency_offset = net.adjacency_offset.data();
    network_view_.adjacency_spring = net.adjacency_spring.data();
    neighbour_ = adjacency_neighbours(net, &pool_);
    network_view_.adjacency_neighbour = neighbour_.data();
    network_view_.rest_length = rest_length_.data();
    network_view_.stiffness = stiffness_.data();
    network_view_.damping = damping_.empty() ? nullptr : damping_.data();
    network_view_.law.law = setup.law;
    network_view_.law.k2_over_k1 = static_cast<Real>(setup.basafa_k2_over_k1);
    network_view_.law.xc = static_cast<Real>(setup.basafa_xc);
    for (const Tetrahedron& t : setup.tetrahedra) corners_.insert(corners_.end(), t.begin(), t.end());
    if (!setup_.elements.empty()) {
      const ElementGeometry& geometry = setup_.elements.geometry;
      rest_inverse_ = convert(geometry.rest_inverse);
      rest_volume_ = convert(geometry.rest_volume);
      corner_force_.assign(geometry.nodes.size(), kernels::CornerForce<Real>{});
      const kernels::StrainTableView table = setup_.strain_stiffness ? strain_table_view(*setup_.strain_stiffness)
                                                                     : kernels::StrainTableView{nullptr, nullptr, 0};
      for (const ElementTerm& term : setup_.elements.terms) {
        TermArrays arrays;
        for (int p = 0; p < kernels::kMostLawParameters; ++p) arrays.parameter[p] = convert(term.parameter[p]);
        arrays.damping = convert(term.stiffness_damping);
        for (std::size_t i = 0; i < term.prony.size() && i < static_cast<std::size_t>(kernels::kMostPronyTerms); ++i)
          arrays.prony_weight[i] = convert(term.prony[i].element_weight);
        const int width = point_state_width(term);
        const int points = static_cast<int>(geometry.size()) * points_per_element(geometry.kind);
        arrays.state.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(points), Real(0));
        if (kernels::element_kind_has_nodal_pass(geometry.kind)) {
          arrays.nodal_pressure.assign(n_, Real(0));
          arrays.nodal_dilatation.assign(n_, Real(0));
        }
        term_arrays_.push_back(std::move(arrays));
        const TermArrays& held = term_arrays_.back();
        const auto data_or_null = [](const std::vector<Real>& values) {
          return values.empty() ? nullptr : values.data();
        };
        kernels::ElementTermView<Real> view{};
        view.law = term.law;
        view.element = geometry.kind;
        view.count = static_cast<int>(geometry.size());
        view.corners = geometry.nodes.data();
        view.corner_slot = geometry.corner_slot.data();
        view.rest_inverse = rest_inverse_.data();
        view.rest_volume = rest_volume_.data();
        for (int p = 0; p < kernels::kMostLawParameters; ++p) view.parameter[p] = data_or_null(held.parameter[p]);
        view.stiffness_damping = data_or_null(held.damping);
        for (int i = 0; i < kernels::kMostPronyTerms; ++i) view.prony_weight[i] = data_or_null(held.prony_weight[i]);
        view.nodal_pressure = data_or_null(held.nodal_pressure);
        view.nodal_dilatation = data_or_null(held.nodal_dilatation);
        view.strain_table = reads_strain_table(term) ? table : kernels::StrainTableView{nullptr, nullptr, 0};
        view.state = {width > 0 ? term_arrays_.back().state.data() : nullptr, width, points};
        view.prony = kernels::PronyConstants<Real>{};
        if (width > 0)
          view.prony = prony_constants_in<Real>(term.prony, stability.time_step,
                                                setup.integrator == Integrator::ImplicitEuler);
        term_views_.push_back(view);
      }
      corner_view_ = {geometry.corner_offset.data(), geometry.corner_index.data(), corner_force_.data()};
    }
    update_point_state(true);
    loads_.mass = mass_.data();
    loads_.fixed = fixed_.data();
    loads_.rest_x = rest_.x.data();
    loads_.rest_y = rest_.y.data();
    loads_.rest_z = rest_.z.data();
    loads_.force_x = force_.x.empty() ? nullptr : force_.x.data();
    loads_.force_y = force_.y.empty() ? nullptr : force_.y.data();
    loads_.force_z = force_.z.empty() ? nullptr : force_.z.data();
    loads_.gravity_x = static_cast<Real>(setup.gravity[0]);
    loads_.gravity_y = static_cast<Real>(setup.gravity[1]);
    loads_.gravity_z = static_cast<Real>(setup.gravity[2]);
    loads_.gamma0 = static_cast<Real>(setup.nodal_damping_gamma0);
    loads_.gamma1 = static_cast<Real>(setup.nodal_damping_gamma1);
    loads_.mass_damping = static_cast<Real>(setup.mass_damping);
    h_ = static_cast<Real>(stability.time_step);
    const Integrator scheme = setup.integrator;
    if (scheme == Integrator::VelocityVerlet || scheme == Integrator::RungeKutta4) {
      stage_position_.resize(n_);
      stage_velocity_.resize(n_);
      next_acceleration_.resize(n_);
    }
    if (scheme == Integrator::RungeKutta4) {
      for (auto& k : rk_velocity_) k.resize(n_);
      for (auto& k : rk_acceleration_) k.resize(n_);
    }
    if (scheme == Integrator::ImplicitEuler) {
      solver_ = std::make_unique<ImplicitSolver>(setup, fixed_, stability.time_step, pool_);
      log_ = ImplicitSolverLog(solver_->method(), setup.implicit.tolerance, implicit_iteration_limit(setup));
    }
  }

  // Contact: the stiffness and damping per vertex and the tools' shapes, in Real, which loads_.contact points at.
  void set_contact(const std::vector<double>& stiffness, const std::vector<double>& damping) override {
    contact_stiffness_.assign(stiffness.begin(), stiffness.end());
    contact_damping_.assign(damping.begin(), damping.end());
    loads_.contact.stiffness = contact_stiffness_.data();
    loads_.contact.damping = contact_damping_.empty() ? nullptr : contact_damping_.data();
  }

  void set_tool_shapes(const std::vector<kernels::ToolShape<double>>& shapes) override {
    tools_.resize(shapes.size());
    for (std::size_t t = 0; t < shapes.size(); ++t) {
      const kernels::ToolShape<double>& s = shapes[t];
      tools_[t] = {static_cast<Real>(s.ax), static_cast<Real>(s.ay), static_cast<Real>(s.az), static_cast<Real>(s.bx),
                   static_cast<Real>(s.by), static_cast<Real>(s.bz), static_cast<Real>(s.radius)};
    }
    loads_.contact.tools = tools_.data();
    loads_.contact.tool_count = static_cast<int>(tools_.size());
  }

  // The setup's material arrays were replaced with arrays of the same sizes: converted again into the buffers the
  // views point at (their sizes, and so the views, are unchanged); the strain table's view and the Prony constants
  // are taken again.
  void refresh_material() override {
    const SpringNetwork& net = setup_.springs;
    std::transform(net.stiffness.begin(), net.stiffness.end(), stiffness_.begin(),
                   [](double k) { return static_cast<Real>(k); });
    std::transform(net.damping.begin(), net.damping.end(), damping_.begin(),
                   [](double c) { return static_cast<Real>(c); });
    const kernels::StrainTableView table = setup_.strain_stiffness ? strain_table_view(*setup_.strain_stiffness)
                                                                   : kernels::StrainTableView{nullptr, nullptr, 0};
    for (std::size_t t = 0; t < term_arrays_.size(); ++t) {
      const ElementTerm& term = setup_.elements.terms[t];
      TermArrays& arrays = term_arrays_[t];
      for (int p = 0; p < kernels::kMostLawParameters; ++p)
        std::transform(term.parameter[p].begin(), term.parameter[p].end(), arrays.parameter[p].begin(),
                       [](double value) { return static_cast<Real>(value); });
      std::transform(term.stiffness_damping.begin(), term.stiffness_damping.end(), arrays.damping.begin(),
                     [](double beta) { return static_cast<Real>(beta); });
      if (reads_strain_table(term)) term_views_[t].strain_table = table;
      // The Prony series' weights and times (the same count: its state keeps its width) take effect from the next
      // step; the history held so far stays.
      if (term_views_[t].prony.count > 0)
        term_views_[t].prony = prony_constants_in<Real>(term.prony, stability_.time_step,
                                                        setup_.integrator == Integrator::ImplicitEuler);
    }
  }

  void run_to(std::size_t end, DiagnosticList& diagnostics) override {
    while (steps_taken_ < end) {
      one_step(diagnostics);
      if (first_non_finite_vertex() < n_) return;
    }
  }

  ProbeReading probe_reading() const override {
    ElementTermStates states;
    for (const TermArrays& arrays : term_arrays_) states.emplace_back(arrays.state.begin(), arrays.state.end());
    return read_probe(setup_, time(), positions(), velocities(), current_stiffness(), &states);
  }

  std::vector<double> current_stiffness() const override {
    std::vector<double> out(stiffness_.size());
    for (std::size_t s = 0; s < out.size(); ++s) out[s] = static_cast<double>(stiffness_[s]);
    return out;
  }

  std::size_t steps_taken() const override { return steps_taken_; }
  double time() const { return static_cast<double>(steps_taken_) * stability_.time_step; }
  std::vector<Point3> positions() const override { return to_points(position_); }
  std::vector<Point3> velocities() const override { return to_points(velocity_); }
  const ImplicitSolverLog& implicit_log() const override { return log_; }
  std::vector<ImplicitStepRecord> take_implicit_steps() override { return log_.take(); }
  const SimulationSetup& setup() const override { return setup_; }

  double kinetic_energy() const override { return sim::kinetic_energy(setup_, velocities()); }

  double potential_energy() const override {
    double energy = elastic_energy(setup_, positions());
    for (std::size_t v = 0; v < n_; ++v) {
      const double p[3] = {static_cast<double>(position_.x[v]), static_cast<double>(position_.y[v]),
                           static_cast<double>(position_.z[v])};
      for (std::size_t axis = 0; axis < 3; ++axis) {
        energy -= setup_.mass[v] * setup_.gravity[axis] * p[axis];
        if (!setup_.external_forces.empty()) energy -= setup_.external_forces[v][axis] * p[axis];
      }
    }
    return energy;
  }

 private:
  kernels::StateView<Real> view(const Vector3Arrays<Real>& p, const Vector3Arrays<Real>& v) const {
    return {p.x.data(), p.y.data(), p.z.data(), v.x.data(), v.y.data(), v.z.data()};
  }

  // a(x, v) for every vertex: the element pass first (when the model has elements), then one gather per vertex with
  // the model's forces, dispatched once per call. With `linearisations` (implicit Euler in double), each term whose
  // kind gives them keeps its elements' linearisations at p there (ElementLinearisations), the forces' bits unchanged.
  void accelerations(const Vector3Arrays<Real>& p, const Vector3Arrays<Real>& v, Vector3Arrays<Real>& a,
                     ElementLinearisations* linearisations = nullptr) {
    const kernels::StateView<Real> state = view(p, v);
    if (!term_views_.empty()) {
      nodal_pass(state);
      // Each term's pass in list order: the first writes the corner forces, the later ones add to them.
      for (std::size_t term = 0; term < term_views_.size(); ++term) {
        const kernels::ElementTermView<Real>& field = term_views_[term];
        kernels::visit_element_term(field.element, field.law, [&](auto kind, auto element_law) {
          using Element = decltype(kind);
          using Law = decltype(element_law);
          if constexpr (std::is_same_v<Real, double> && kernels::HasForcesAndLinearisation<Element, Law>::value) {
            if (linearisations != nullptr) {
              using Lin = typename Element::template Linearisation<Law>;
              linearisations->hold<Lin>(term, static_cast<std::size_t>(field.count));
              pool_.run(static_cast<std::size_t>(field.count), [&](std::size_t begin, std::size_t end) {
                for (std::size_t e = begin; e < end; ++e) {
                  Lin lin{};  // as ElementTangents::stiffness starts its own
                  if (term == 0) {
                    kernels::element_node_forces_linearised<Element, Law, false>(static_cast<int>(e), field, state,
                                                                                 corner_force_.data(), lin);
                  } else {
                    kernels::element_node_forces_linearised<Element, Law, true>(static_cast<int>(e), field, state,
                                                                                corner_force_.data(), lin);
                  }
                  linearisations->store(term, e, lin);
                }
              });
              return;
            }
          }
          pool_.run(static_cast<std::size_t>(field.count), [&](std::size_t begin, std::size_t end) {
            for (std::size_t e = begin; e < end; ++e) {
              const int element = static_cast<int>(e);
              if (term == 0) {
                kernels::element_node_forces<Element, Law, false>(element, field, state, corner_force_.data());
              } else {
                kernels::element_node_forces<Element, Law, true>(element, field, state, corner_force_.data());
              }
            }
          });
        });
      }
      if (setup_.springs.size() == 0) {
        vertex_pass(kernels::ElementForces<Real>{corner_view_}, state, a);
      } else {
        vertex_pass(kernels::SpringAndElementForces<Real>{network_view_, corner_view_}, state, a);
      }
      return;
    }
    vertex_pass(kernels::SpringForces<Real>{network_view_}, state, a);
  }

  // Where the element kind reads nodal values (kernels::element_kind_has_nodal_pass): every term's nodal pressure at
  // `state`, before any term's element pass (the shares use the corner-force slots that those passes then write).
  void nodal_pass(const kernels::StateView<Real>& state) {
    for (std::size_t term = 0; term < term_views_.size(); ++term) {
      const kernels::ElementTermView<Real>& field = term_views_[term];
      if (field.nodal_pressure == nullptr) continue;
      kernels::visit_element_term(field.element, field.law, [&](auto kind, auto element_law) {
        using Element = decltype(kind);
        using Law = decltype(element_law);
        pool_.run(static_cast<std::size_t>(field.count), [&](std::size_t begin, std::size_t end) {
          for (std::size_t e = begin; e < end; ++e)
            kernels::element_nodal_shares<Element, Law>(static_cast<int>(e), field, state, corner_force_.data());
        });
      });
      TermArrays& arrays = term_arrays_[term];
      pool_.run(n_, [&](std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v)
          kernels::nodal_pressure_at(static_cast<int>(v), corner_view_, arrays.nodal_pressure[v],
                                     arrays.nodal_dilatation[v]);
      });
    }
  }

  template <typename Forces>
  void vertex_pass(const Forces& forces, const kernels::StateView<Real>& state, Vector3Arrays<Real>& a) {
    pool_.run(n_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        kernels::vertex_acceleration(static_cast<int>(i), forces, state, loads_, a.x[i], a.y[i], a.z[i]);
      }
    });
  }

  void one_step(DiagnosticList& diagnostics) {
    apply_probe(time(), true);
    if (setup_.strain_stiffness && !setup_.springs.stiffness.empty()) look_up_stiffness();
    step(diagnostics);
    ++steps_taken_;
    apply_probe(time(), false);
    update_point_state(false);
  }

  // Each stateful term's state after an accepted step, at the positions held (the step's end, probe applied); with
  // `jump`, the history of a jump from rest to the positions held (the start: prony_constants at dt = 0).
  void update_point_state(bool jump) {
    const kernels::StateView<Real> state = view(position_, velocity_);
    for (std::size_t term = 0; term < term_views_.size(); ++term) {
      kernels::ElementTermView<Real> field = term_views_[term];
      if (field.prony.count == 0) continue;
      if (jump) field.prony = prony_constants_in<Real>(setup_.elements.terms[term].prony, 0.0, false);
      kernels::visit_element_term(field.element, field.law, [&](auto kind, auto element_law) {
        using Element = decltype(kind);
        using Law = decltype(element_law);
        pool_.run(static_cast<std::size_t>(field.count), [&](std::size_t begin, std::size_t end) {
          for (std::size_t e = begin; e < end; ++e)
            kernels::element_state_update<Element, Law>(static_cast<int>(e), field, state);
        });
      });
    }
  }

  // The element kind's own test (kernels::element_inverted) where the scene has element terms, else the tetrahedra's
  // signed volumes.
  InversionCount count_inversions() const override {
    InversionCount found;
    const bool elements = !setup_.elements.empty();
    const int kind = elements ? setup_.elements.geometry.kind : kernels::kTetrahedronKind;
    const int* nodes = elements ? setup_.elements.geometry.nodes.data() : corners_.data();
    for (std::size_t e = 0; e < setup_.tetrahedra.size(); ++e) {
      if (!kernels::element_inverted(kind, static_cast<int>(e), nodes, position_.x.data(), position_.y.data(),
                                     position_.z.data()))
        continue;
      if (found.count == 0) found.first = static_cast<std::int32_t>(e);
      ++found.count;
    }
    return found;
  }

  void save_checkpoint() override {
    checkpoint_position_ = position_;
    checkpoint_velocity_ = velocity_;
    checkpoint_acceleration_ = acceleration_;
    checkpoint_have_acceleration_ = have_acceleration_;
    checkpoint_step_ = steps_taken_;
    for (TermArrays& arrays : term_arrays_) arrays.checkpoint_state = arrays.state;
    if (solver_) {
      checkpoint_warm_start_ = solver_->warm_start();
      log_.save(steps_taken_);
    }
  }

  void restore_checkpoint() override {
    position_ = checkpoint_position_;
    velocity_ = checkpoint_velocity_;
    acceleration_ = checkpoint_acceleration_;
    have_acceleration_ = checkpoint_have_acceleration_;
    steps_taken_ = checkpoint_step_;
    // Copied into the buffers the views point at.
    for (TermArrays& arrays : term_arrays_) std::copy(arrays.checkpoint_state.begin(), arrays.checkpoint_state.end(),
                                                      arrays.state.begin());
    if (solver_) {
      solver_->set_warm_start(checkpoint_warm_start_);
      log_.restore();
    }
  }

  template <typename Update>
  void for_each_vertex(Update update) {
    pool_.run(n_, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) update(i);
    });
  }

  bool step(DiagnosticList& diagnostics) {
    const Real h = h_;
    switch (setup_.integrator) {
      case Integrator::ForwardEuler:
        accelerations(position_, velocity_, acceleration_);
        for_each_vertex([&](std::size_t i) {
          kernels::forward_euler_update(position_.x[i], velocity_.x[i], acceleration_.x[i], h);
          kernels::forward_euler_update(position_.y[i], velocity_.y[i], acceleration_.y[i], h);
          kernels::forward_euler_update(position_.z[i], velocity_.z[i], acceleration_.z[i], h);
        });
        return true;
      case Integrator::SemiImplicitEuler:
        accelerations(position_, velocity_, acceleration_);
        for_each_vertex([&](std::size_t i) {
          kernels::semi_implicit_euler_update(position_.x[i], velocity_.x[i], acceleration_.x[i], h);
          kernels::semi_implicit_euler_update(position_.y[i], velocity_.y[i], acceleration_.y[i], h);
          kernels::semi_implicit_euler_update(position_.z[i], velocity_.z[i], acceleration_.z[i], h);
        });
        return true;
      case Integrator::VelocityVerlet:
        if (!have_acceleration_) accelerations(position_, velocity_, acceleration_);
        for_each_vertex([&](std::size_t i) {
          kernels::verlet_position_update(position_.x[i], velocity_.x[i], acceleration_.x[i], h, stage_velocity_.x[i]);
          kernels::verlet_position_update(position_.y[i], velocity_.y[i], acceleration_.y[i], h, stage_velocity_.y[i]);
          kernels::verlet_position_update(position_.z[i], velocity_.z[i], acceleration_.z[i], h, stage_velocity_.z[i]);
        });
        accelerations(position_, stage_velocity_, next_acceleration_);
        for_each_vertex([&](std::size_t i) {
          kernels::verlet_velocity_update(velocity_.x[i], acceleration_.x[i], next_acceleration_.x[i], h);
          kernels::verlet_velocity_update(velocity_.y[i], acceleration_.y[i], next_acceleration_.y[i], h);
          kernels::verlet_velocity_update(velocity_.z[i], acceleration_.z[i], next_acceleration_.z[i], h);
        });
        std::swap(acceleration_, next_acceleration_);
        have_acceleration_ = true;
        return true;
      case Integrator::RungeKutta4:
        runge_kutta4_step(h);
        return true;
      case Integrator::ImplicitEuler:
        return implicit_euler_step(diagnostics);
    }
    return false;
  }

  void runge_kutta4_step(Real h) {
    // Stage s evaluates the derivative at y0 + c_s h k_{s-1}: c = 0, 1/2, 1/2, 1.
    const Real offsets[4] = {Real(0), h / Real(2), h / Real(2), h};
    for (std::size_t s = 0; s < 4; ++s) {
      if (s == 0) {
        rk_velocity_[0] = velocity_;
        accelerations(position_, velocity_, rk_acceleration_[0]);
        continue;
      }
      const Real c = offsets[s];
      const Vector3Arrays<Real>& kv = rk_velocity_[s - 1];
      const Vector3Arrays<Real>& ka = rk_acceleration_[s - 1];
      for_each_vertex([&](std::size_t i) {
        stage_position_.x[i] = position_.x[i] + c * kv.x[i];
        stage_position_.y[i] = position_.y[i] + c * kv.y[i];
        stage_position_.z[i] = position_.z[i] + c * kv.z[i];
        stage_velocity_.x[i] = velocity_.x[i] + c * ka.x[i];
        stage_velocity_.y[i] = velocity_.y[i] + c * ka.y[i];
        stage_velocity_.z[i] = velocity_.z[i] + c * ka.z[i];
      });
      rk_velocity_[s] = stage_velocity_;
      accelerations(stage_position_, stage_velocity_, rk_acceleration_[s]);
    }
    const auto& kv = rk_velocity_;
    const auto& ka = rk_acceleration_;
    for_each_vertex([&](std::size_t i) {
      if (fixed_[i] == kernels::kAllAxesFixed) return;
      position_.x[i] = kernels::runge_kutta4_combine(position_.x[i], kv[0].x[i], kv[1].x[i], kv[2].x[i], kv[3].x[i], h);
      position_.y[i] = kernels::runge_kutta4_combine(position_.y[i], kv[0].y[i], kv[1].y[i], kv[2].y[i], kv[3].y[i], h);
      position_.z[i] = kernels::runge_kutta4_combine(position_.z[i], kv[0].z[i], kv[1].z[i], kv[2].z[i], kv[3].z[i], h);
      velocity_.x[i] = kernels::runge_kutta4_combine(velocity_.x[i], ka[0].x[i], ka[1].x[i], ka[2].x[i], ka[3].x[i], h);
      velocity_.y[i] = kernels::runge_kutta4_combine(velocity_.y[i], ka[0].y[i], ka[1].y[i], ka[2].y[i], ka[3].y[i], h);
      velocity_.z[i] = kernels::runge_kutta4_combine(velocity_.z[i], ka[0].z[i], ka[1].z[i], ka[2].z[i], ka[3].z[i], h);
    });
  }

  // Baraff & Witkin's linearised backward Euler (kernels/implicit_math.h), (M + h D + h^2 K) dv = h (f0 - h K v0)
  // with the model's tangent, solved by implicit_solver.h (a direct factorisation or a preconditioned CG, each step
  // recorded in the log); held axes keep their velocity.
  bool implicit_euler_step(DiagnosticList& diagnostics) {
    accelerations(position_, velocity_, acceleration_, &linearisations_);
    // The solver's interleaved copies, by the workers: on one thread they were a serial part of the step.
    implicit_x_.resize(3 * n_);
    implicit_v_.resize(3 * n_);
    implicit_a_.resize(3 * n_);
    const auto interleave = [](const Vector3Arrays<Real>& from, std::vector<double>& to, std::size_t i) {
      to[3 * i] = static_cast<double>(from.x[i]);
      to[3 * i + 1] = static_cast<double>(from.y[i]);
      to[3 * i + 2] = static_cast<double>(from.z[i]);
    };
    for_each_vertex([&](std::size_t i) {
      interleave(position_, implicit_x_, i);
      interleave(velocity_, implicit_v_, i);
      interleave(acceleration_, implicit_a_, i);
    });
    implicit_k_.resize(stiffness_.size());
    for (std::size_t s = 0; s < stiffness_.size(); ++s) implicit_k_[s] = static_cast<double>(stiffness_[s]);
    const bool contact = loads_.contact.tool_count > 0;
    if (contact) contact_.start(implicit_x_, implicit_v_, static_cast<double>(h_));
    const ImplicitSolve solve =
        solver_->solve(implicit_x_, implicit_v_, implicit_a_, implicit_k_, static_cast<double>(h_), pool_,
                       implicit_dv_, contact ? &contact_ : nullptr, setup_.implicit.contact_rounds, &linearisations_);
    linearisations_.release();
    if (solve.direct_failed) log_.fallback();
    const ImplicitStepRecord record{steps_taken_ + 1, solve.iterations, solve.relative_residual, !solve.converged};
    if (log_.record(record)) {
      diagnostics.warning(setup_.source_range, "cg-not-converged",
                          cg_stopped_message(solve.direct_failed ? ImplicitMethod::ConjugateGradient
                                                                 : solver_->method(),
                                             record.step, record.iterations, record.relative_residual,
                                             setup_.implicit.tolerance));
    }
    if (!solve.settled)
      log_.contact_unsettled(steps_taken_ + 1, setup_.implicit.contact_rounds, setup_.source_range, diagnostics);
    const std::vector<double>& dv = implicit_dv_;
    for_each_vertex([&](std::size_t i) {
      if (fixed_[i] == kernels::kAllAxesFixed) return;
      velocity_.x[i] += static_cast<Real>(dv[3 * i]);
      velocity_.y[i] += static_cast<Real>(dv[3 * i + 1]);
      velocity_.z[i] += static_cast<Real>(dv[3 * i + 2]);
      position_.x[i] += h_ * velocity_.x[i];
      position_.y[i] += h_ * velocity_.y[i];
      position_.z[i] += h_ * velocity_.z[i];
    });
    return true;
  }

  std::size_t first_non_finite_vertex() const override {
    for (std::size_t v = 0; v < n_; ++v) {
      if (!(std::isfinite(position_.x[v]) && std::isfinite(position_.y[v]) && std::isfinite(position_.z[v]) &&
            std::isfinite(velocity_.x[v]) && std::isfinite(velocity_.y[v]) && std::isfinite(velocity_.z[v])))
        return v;
    }
    return n_;
  }

  // Displacement probes: positions (and, before a step, the ramp's velocity) of the probe vertices at time t.
  // Force probes: their share of the force for the step from t.
  void apply_probe(double t, bool before_step) {
    if (!setup_.probe) return;
    const ProbeLoad& probe = *setup_.probe;
    if (probe.mode == ProbeLoad::Mode::Force) {
      if (!before_step) return;
      const double share = kernels::probe_ramp_share(t, probe.ramp_time, probe.cycles);
      const double count = static_cast<double>(probe.vertices.size());
      for (const auto vertex : probe.vertices) {
        const auto v = static_cast<std::size_t>(vertex);
        const Point3 base = setup_.external_forces.empty() ? Point3{0.0, 0.0, 0.0} : setup_.external_forces[v];
        force_.x[v] = static_cast<Real>(base[0] + share * probe.target[0] / count);
        force_.y[v] = static_cast<Real>(base[1] + share * probe.target[1] / count);
        force_.z[v] = static_cast<Real>(base[2] + share * probe.target[2] / count);
      }
      return;
    }
    const kernels::ProbeRamp ramp = kernels::probe_ramp(t, probe.ramp_time, probe.cycles);
    for (const auto vertex : probe.vertices) {
      const auto v = static_cast<std::size_t>(vertex);
      const Point3& start = start_position(setup_, v);
      kernels::probe_prescribed_axis(ramp, start[0], probe.target[0], probe.ramp_time, before_step, position_.x[v],
                                     velocity_.x[v]);
      kernels::probe_prescribed_axis(ramp, start[1], probe.target[1], probe.ramp_time, before_step, position_.y[v],
                                     velocity_.y[v]);
      kernels::probe_prescribed_axis(ramp, start[2], probe.target[2], probe.ramp_time, before_step, position_.z[v],
                                     velocity_.z[v]);
    }
  }

  // k = modulus(strain) * stiffness_per_modulus for every spring, from the current positions.
  void look_up_stiffness() {
    const SpringNetwork& net = setup_.springs;
    const StrainStiffnessTable& table = *setup_.strain_stiffness;
    const kernels::StrainTableView view = strain_table_view(table);
    pool_.run(net.size(), [&](std::size_t begin, std::size_t end) {
      for (std::size_t s = begin; s < end; ++s) {
        const auto a = static_cast<std::size_t>(net.first[s]), b = static_cast<std::size_t>(net.second[s]);
        stiffness_[s] = static_cast<Real>(kernels::strain_table_stiffness(
            view, static_cast<double>(position_.x[b]) - static_cast<double>(position_.x[a]),
            static_cast<double>(position_.y[b]) - static_cast<double>(position_.y[a]),
            static_cast<double>(position_.z[b]) - static_cast<double>(position_.z[a]), net.rest_length[s],
            table.stiffness_per_modulus[s]));
      }
    });
  }

  static std::vector<Point3> to_points(const Vector3Arrays<Real>& a) {
    std::vector<Point3> out(a.x.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = {static_cast<double>(a.x[i]), static_cast<double>(a.y[i]), static_cast<double>(a.z[i])};
    }
    return out;
  }

  const SimulationSetup& setup_;  // the Simulation's: the views below point into it
  StabilityReport stability_;
  WorkerPool pool_;
  std::size_t n_;
  std::vector<Real> rest_length_, stiffness_, damping_, mass_;
  std::vector<unsigned char> fixed_;
  std::vector<Real> contact_stiffness_, contact_damping_;
  std::vector<kernels::ToolShape<Real>> tools_;
  Vector3Arrays<Real> position_, velocity_, rest_, acceleration_, force_;
  Vector3Arrays<Real> stage_position_, stage_velocity_, next_acceleration_;
  Vector3Arrays<Real> rk_velocity_[4], rk_acceleration_[4];
  kernels::SpringNetworkView<Real> network_view_{};
  kernels::VertexLoads<Real> loads_{};
  std::vector<int> corners_;             // 4 per tetrahedron
  std::vector<std::int32_t> neighbour_;  // the other endpoint of each CSR entry (adjacency_neighbours)
  // The element terms in Real: the geometry the terms share, each term's parameters and damping, and its view.
  struct TermArrays {
    std::vector<Real> parameter[kernels::kMostLawParameters];
    std::vector<Real> damping;
    std::vector<Real> prony_weight[kernels::kMostPronyTerms];  // per element where the term's weight varies
    std::vector<Real> state, checkpoint_state;  // per-point state (view.state) and its checkpoint
    // Per vertex, a kind with a nodal pass (view.nodal_pressure, view.nodal_dilatation); empty for the others.
    std::vector<Real> nodal_pressure, nodal_dilatation;
  };
  std::vector<Real> rest_inverse_, rest_volume_;
  std::vector<TermArrays> term_arrays_;  // the views point into its vectors' buffers, which moves keep
  std::vector<kernels::ElementTermView<Real>> term_views_;
  std::vector<kernels::CornerForce<Real>> corner_force_;
  kernels::CornerForceView<Real> corner_view_{};
  Real h_ = Real(0);
  bool have_acceleration_ = false;
  std::size_t steps_taken_ = 0;
  Vector3Arrays<Real> checkpoint_position_, checkpoint_velocity_, checkpoint_acceleration_;
  bool checkpoint_have_acceleration_ = false;
  std::size_t checkpoint_step_ = 0;
  // Implicit Euler: the solver, its log, the state in double for the solver, and the warm start at the checkpoint.
  std::unique_ptr<ImplicitSolver> solver_;
  ImplicitSolverLog log_;
  std::vector<double> implicit_x_, implicit_v_, implicit_a_, implicit_k_, implicit_dv_, checkpoint_warm_start_;
  // The elements' linearisations from the step's force pass, for its tangent.
  ElementLinearisations linearisations_;
  // The tools' contact in the solve (read through loads_.contact).
  ImplicitContact<Real> contact_{loads_.contact, fixed_};
};

// The CPU engine of a batch: each scene's CpuScene, run side by side on a pool of workers over the scenes (a scene's
// own vertex loops use its setup's threads); one check per run. A scene alone stops at the step that made it
// non-finite (exact, as its steps check every vertex); in a batch the others run on, so the supervisor replays.
class CpuEngine final : public SteppingEngine {
 public:
  CpuEngine(const std::vector<SimulationSetup>& scenes, const std::vector<StabilityReport>& stability,
            unsigned batch_threads)
      : pool_(scenes.size() > 1 ? resolve_thread_count(batch_threads, scenes.size(), 2) : 1) {
    vertex_begin_.push_back(0);
    for (std::size_t s = 0; s < scenes.size(); ++s) {
      if (scenes[s].precision == Precision::Float) {
        scenes_.push_back(std::make_unique<CpuScene<float>>(scenes[s], stability[s]));
      } else {
        scenes_.push_back(std::make_unique<CpuScene<double>>(scenes[s], stability[s]));
      }
      vertex_begin_.push_back(vertex_begin_.back() + scenes[s].rest_positions.size());
    }
  }

  const char* label() const override { return ""; }
  std::size_t steps_taken() const override {
    std::size_t least = scenes_.front()->steps_taken();
    for (const auto& scene : scenes_) least = std::min(least, scene->steps_taken());
    return least;
  }
  std::size_t checks_per_run() const override { return 1; }
  std::size_t most_steps_per_run() const override { return std::numeric_limits<std::size_t>::max(); }

  bool run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) override {
    const std::size_t end = ends.back();
    if (scenes_.size() == 1) {
      scenes_.front()->run_to(end, diagnostics);
      return true;
    }
    // Each scene's warnings into its own list, appended in scene order: the same text whatever the scheduling.
    std::vector<DiagnosticList> scene_diagnostics(scenes_.size());
    pool_.run(
        scenes_.size(),
        [&](std::size_t begin, std::size_t stop) {
          for (std::size_t s = begin; s < stop; ++s) scenes_[s]->run_to(end, scene_diagnostics[s]);
        },
        1);
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      for (Diagnostic diagnostic : scene_diagnostics[s].items()) {
        diagnostic.message = "scene " + std::to_string(s) + ": " + diagnostic.message;
        diagnostics.add(std::move(diagnostic));
      }
    }
    return true;
  }
  void select_check(std::size_t) override {}
  std::optional<int> first_non_finite_vertex(DiagnosticList&) override {
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      const std::size_t v = scenes_[s]->first_non_finite_vertex();
      if (v < vertex_begin_[s + 1] - vertex_begin_[s]) return static_cast<int>(vertex_begin_[s] + v);
    }
    return static_cast<int>(vertex_begin_.back());
  }
  bool non_finite_is_exact() const override { return scenes_.size() == 1; }
  bool count_inverted(std::vector<unsigned>& counts, std::vector<int>& firsts, DiagnosticList&) override {
    counts.resize(scenes_.size());
    firsts.resize(scenes_.size());
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      const InversionCount found = scenes_[s]->count_inversions();
      counts[s] = static_cast<unsigned>(found.count);
      firsts[s] = found.first;
    }
    return true;
  }
  bool save_checkpoint(DiagnosticList&) override {
    for (const auto& scene : scenes_) scene->save_checkpoint();
    return true;
  }
  bool restore_checkpoint(DiagnosticList&) override {
    for (const auto& scene : scenes_) scene->restore_checkpoint();
    return true;
  }
  int implicit_max_iterations_used() const override {
    int most = 0;
    for (const auto& scene : scenes_) most = std::max(most, scene->implicit_log().report().iterations_max);
    return most;
  }
  ImplicitSolverReport implicit_solver(std::size_t scene) const override {
    return scenes_[scene]->implicit_log().report();
  }
  std::vector<ImplicitStepRecord> take_implicit_steps(std::size_t scene) override {
    return scenes_[scene]->take_implicit_steps();
  }

  std::vector<Point3> positions(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->positions();
  }
  std::vector<Point3> velocities(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->velocities();
  }
  bool scene_states(std::vector<std::vector<Point3>>& positions, std::vector<std::vector<Point3>>* velocities,
                    DiagnosticList&) const override {
    positions.resize(scenes_.size());
    if (velocities != nullptr) velocities->resize(scenes_.size());
    for (std::size_t s = 0; s < scenes_.size(); ++s) {
      positions[s] = scenes_[s]->positions();
      if (velocities != nullptr) (*velocities)[s] = scenes_[s]->velocities();
    }
    return true;
  }
  std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->kinetic_energy();
  }
  std::optional<double> potential_energy(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->potential_energy();
  }
  std::optional<double> elastic_energy(std::size_t scene, DiagnosticList&) const override {
    return sim::elastic_energy(setup_of(scene), scenes_[scene]->positions());
  }
  std::optional<double> largest_displacement(std::size_t scene, DiagnosticList&) const override {
    const std::vector<Point3> now = scenes_[scene]->positions();
    const SimulationSetup& setup = setup_of(scene);
    const std::vector<Point3>& start = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    double largest = 0.0;
    for (std::size_t v = 0; v < now.size() && v < start.size(); ++v)
      largest = std::max(largest, distance(now[v], start[v]));
    return largest;
  }
  bool reduces_in_place() const override { return false; }
  ProbeReading probe_reading(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->probe_reading();
  }
  std::vector<double> current_stiffness(std::size_t scene, DiagnosticList&) const override {
    return scenes_[scene]->current_stiffness();
  }
  bool set_contact(std::size_t scene, const std::vector<double>& stiffness, const std::vector<double>& damping,
                   DiagnosticList&) override {
    scenes_[scene]->set_contact(stiffness, damping);
    return true;
  }
  bool set_tool_shapes(std::size_t scene, const std::vector<kernels::ToolShape<double>>& shapes,
                       DiagnosticList&) override {
    scenes_[scene]->set_tool_shapes(shapes);
    return true;
  }
  bool refresh_material(std::size_t scene, DiagnosticList&) override {
    scenes_[scene]->refresh_material();
    return true;
  }

 private:
  const SimulationSetup& setup_of(std::size_t scene) const { return scenes_[scene]->setup(); }

  std::vector<std::unique_ptr<CpuSceneBase>> scenes_;
  std::vector<std::size_t> vertex_begin_;
  mutable WorkerPool pool_;
};

}  // namespace

std::unique_ptr<SteppingEngine> create_cpu_engine(const std::vector<SimulationSetup>& scenes,
                                                  const std::vector<StabilityReport>& stability,
                                                  unsigned batch_threads) {
  return std::make_unique<CpuEngine>(scenes, stability, batch_threads);
}

}  // namespace fmpc::sim
