// The Simulation interface over a DemSystem of one compile-time contact model. Included only
// by the files that instantiate it (simulation_<law>.cpp), so each law's kernels are
// compiled once.
#pragma once
#include <Kokkos_Core.hpp>
#include <numeric>

#include "scenarios/api/simulation.hpp"
#include "scenarios/common/contact_network.hpp"

namespace granular::api {

template <class Model>
class SimulationOf final : public Simulation {
 public:
  using Exec = Kokkos::DefaultExecutionSpace;
  using System = DemSystem<Exec, Model>;

  SimulationOf(const Model& model, std::string name, Particles<Exec> particles,
               std::vector<double> density, const PeriodicBox& box, const DemParams& params,
               const ConfigState* history)
      : name_(std::move(name)),
        sys_(std::move(particles), box, model, params),
        density_(std::move(density)) {
    if (history) restore_history(sys_, *history);
    auto m = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), sys_.particles().mass);
    mass_ = 0;
    for (int i = 0; i < sys_.particles().n; ++i) mass_ += m(i);
  }

  void step(long n) override { sys_.step(n); }
  void set_strain_rate(const std::array<double, 3>& r) override {
    sys_.set_strain_rate(r[0], r[1], r[2]);
    rate_ = r;
  }
  std::array<double, 3> strain_rate() const override { return rate_; }
  double time() const override { return sys_.time(); }
  long steps() const override { return sys_.steps(); }
  PeriodicBox box() const override { return sys_.box(); }
  const DemParams& params() const override { return sys_.params(); }
  int size() const override { return sys_.particles().n; }
  double particle_volume() const override { return sys_.particle_volume(); }
  double mass() const override { return mass_; }
  std::string model_name() const override { return name_; }

  Measurements measure() const override { return sys_.measure(); }
  void check_health(const Measurements& m) const override { sys_.check_health(m); }

  HostParticles particles() const override { return particles_by_id(); }

  std::vector<double> forces() const override {
    const auto& p = sys_.particles();
    auto f = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.f);
    auto id = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p.id);
    std::vector<double> out(3 * static_cast<size_t>(p.n));
    for (int i = 0; i < p.n; ++i)
      for (int d = 0; d < 3; ++d) out[3 * static_cast<size_t>(id(i)) + d] = f(i, d);
    return out;
  }

  ContactNetwork contacts() const override { return contact_network(sys_); }

  void set_walls(const std::vector<WallSpec>& walls) override { sys_.set_walls(walls); }
  std::vector<WallLoad> wall_loads() const override { return sys_.wall_loads(); }

  long strain_to_phi(double target, double rate, long every) override {
    const long n = granular::strain_to_phi(sys_, target, rate, every, nullptr);
    rate_ = {0, 0, 0};
    return n;
  }
  double relax(double ratio, long max_steps, long every) override {
    rate_ = {0, 0, 0};
    return granular::relax(sys_, ratio, max_steps, false, every);
  }
  ServoResult servo_to_pressure(double target, const ServoSettings& s) override {
    const ServoResult r = granular::servo_to_pressure(sys_, target, mass_ / sys_.box().volume(), s);
    rate_ = {0, 0, 0};
    return r;
  }
  Moduli probe_moduli(double amplitude, long strain_steps, long relax_steps) override {
    rate_ = {0, 0, 0};
    return granular::probe_moduli(sys_, amplitude, strain_steps, relax_steps);
  }
  Moduli probe_moduli_restarting(double amplitude, long strain_steps, long relax_steps,
                                 int orientations) override {
    const ConfigState c = save();
    auto make = [&] { return restart_system<System>(c, sys_.model(), sys_.params()); };
    return granular::probe_moduli_restarting(make, amplitude, strain_steps, relax_steps, nullptr,
                                             orientations);
  }

  ConfigState save() const override {
    ConfigState c = snapshot(sys_, density_, sys_.measure().pressure);
    return c;
  }
  std::unique_ptr<Simulation> restart(const ConfigState& c) const override {
    return std::make_unique<SimulationOf>(sys_.model(), name_, particles_from<Exec>(c),
                                          c.particles.density, c.box, sys_.params(), &c);
  }

 private:
  HostParticles particles_by_id() const {
    const auto& p = sys_.particles();
    auto h = Kokkos::HostSpace();
    auto x = Kokkos::create_mirror_view_and_copy(h, p.x);
    auto v = Kokkos::create_mirror_view_and_copy(h, p.v);
    auto w = Kokkos::create_mirror_view_and_copy(h, p.w);
    auto r = Kokkos::create_mirror_view_and_copy(h, p.radius);
    auto s = Kokkos::create_mirror_view_and_copy(h, p.species);
    auto id = Kokkos::create_mirror_view_and_copy(h, p.id);
    HostParticles out;
    out.resize(p.n);
    for (int i = 0; i < p.n; ++i) {
      const int k = id(i);
      out.x[k] = x(i, 0), out.y[k] = x(i, 1), out.z[k] = x(i, 2);
      out.vx[k] = v(i, 0), out.vy[k] = v(i, 1), out.vz[k] = v(i, 2);
      out.wx[k] = w(i, 0), out.wy[k] = w(i, 1), out.wz[k] = w(i, 2);
      out.radius[k] = r(i);
      out.species[k] = s(i);
      out.density[k] = density_[static_cast<size_t>(k)];  // mass = density * 4/3 pi a^3
    }
    return out;
  }

  std::string name_;
  System sys_;
  std::vector<double> density_;  // by identity
  double mass_ = 0;
  std::array<double, 3> rate_ = {0, 0, 0};
};

template <class Model>
std::unique_ptr<Simulation> simulation_of(const Model& model, const std::string& name,
                                          Particles<Kokkos::DefaultExecutionSpace> particles,
                                          std::vector<double> density, const PeriodicBox& box,
                                          const DemParams& params, const ConfigState* history) {
  return std::make_unique<SimulationOf<Model>>(model, name, std::move(particles),
                                               std::move(density), box, params, history);
}

// The explicit instantiation of simulation_of for one model type, in its law's file.
#define GRANULAR_SIMULATION_OF(...)                                                     \
  template std::unique_ptr<Simulation> simulation_of<__VA_ARGS__>(                      \
      const __VA_ARGS__&, const std::string&, Particles<Kokkos::DefaultExecutionSpace>, \
      std::vector<double>, const PeriodicBox&, const DemParams&, const ConfigState*);

}  // namespace granular::api
